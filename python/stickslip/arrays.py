"""Answers as numpy arrays and pandas frames (``pip install
'stickslip[arrays]'``, or Debian's python3-numpy and python3-pandas).

The client itself never needs them: this module imports them when one of
its functions is called, and says what to install when they are missing.

- ``samples(answer)``: an orbit's or a simulation's samples as columns.
- ``basins(answer)``: a /basins answer's labels as a 2-D integer array,
  with the attractors and the axes' values.
- ``map_frame(lines)``: a /map's cells, one row per cell and orbit.
- ``family_frame(answer)``: a /continue family's points, and its special
  points marked.
"""

from __future__ import annotations

import base64
from typing import (TYPE_CHECKING, Any, Dict, Iterable, List, Mapping,
                    NamedTuple, Tuple)

if TYPE_CHECKING:
    import numpy
    import numpy.typing
    import pandas

    Array = numpy.typing.NDArray[Any]

JSON = Dict[str, Any]


def _numpy() -> Any:
    try:
        import numpy
    except ImportError as e:
        raise ImportError("stickslip.arrays needs numpy: pip install "
                          "'stickslip[arrays]' (or apt-get install "
                          "python3-numpy)") from e
    return numpy


def _pandas() -> Any:
    try:
        import pandas
    except ImportError as e:
        raise ImportError("stickslip.arrays needs pandas for frames: pip "
                          "install 'stickslip[arrays]' (or apt-get install "
                          "python3-pandas)") from e
    return pandas


def _sample_columns(source: Mapping[str, Any]) -> Mapping[str, Any]:
    """The samples object of a /simulate answer, of one orbit of /orbit, or
    that object itself."""
    got = source.get("samples")
    if isinstance(got, Mapping):
        return got
    if "t" in source:
        return source
    raise ValueError("no samples here: ask for them with \"samples\"")


def samples(source: Mapping[str, Any]) -> Dict[str, "Array"]:
    """The sample columns (``t``, ``x1``, ``x2``, ``v1``, ``v2``,
    ``force``, ``F1``, ``F2``: float arrays; ``mode``: an array of
    strings), each as long as ``t``."""
    np = _numpy()
    out: Dict[str, Array] = {}
    for name, col in _sample_columns(source).items():
        if name == "mode":
            out[name] = np.array(col, dtype=str)
        else:
            out[name] = np.array(col, dtype=float)
    return out


def samples_frame(source: Mapping[str, Any]) -> "pandas.DataFrame":
    """The samples as a frame, one row a sample."""
    pd = _pandas()
    return pd.DataFrame(samples(source))


class Basins(NamedTuple):
    """``labels[i, j]``: the label of the cell at ``axes[0]``'s i-th value
    and ``axes[1]``'s j-th (an attractor's ``label``, or ``unresolved``,
    or ``perpetual_slip``); ``attractors``: as the answer lists them;
    ``axes``: each axis's variable and its values."""
    labels: "Array"
    attractors: List[JSON]
    axes: List[Tuple[str, "Array"]]
    unresolved: int
    perpetual_slip: int


def basins(answer: Mapping[str, Any]) -> Basins:
    np = _numpy()
    lab = answer["labels"]
    if lab.get("encoding") != "base64":
        raise ValueError("labels encoded as %r" % lab.get("encoding"))
    raw = base64.b64decode(lab["data"])
    rows, cols = int(lab["rows"]), int(lab["cols"])
    labels = np.frombuffer(raw, dtype=np.uint8).reshape(rows, cols)
    axes = [(str(a["variable"]),
             np.linspace(float(a["from"]), float(a["to"]), int(a["n"])))
            for a in answer.get("input", {}).get("axes", [])]
    return Basins(labels.astype(np.int64), list(answer["attractors"]), axes,
                  int(lab["unresolved"]), int(lab["perpetual_slip"]))


def _flat(orbit: Mapping[str, Any]) -> JSON:
    """An orbit's fields as frame columns: a margin object by its value."""
    row: JSON = {}
    for k, v in orbit.items():
        row[k] = v.get("value") if isinstance(v, Mapping) and "value" in v \
            else v
    return row


def map_frame(lines: Iterable[Mapping[str, Any]]) -> "pandas.DataFrame":
    """A /map's cells, one row per cell and orbit (a cell without an orbit:
    one row whose ``orbit`` is -1): the cell's ``index`` as ``i``, ``j``,
    its parameters from ``at``, ``complete``, the orbit's place in the cell
    as ``orbit`` and its fields (``min_margin`` by its value; ``durations``
    and ``multipliers`` as lists)."""
    pd = _pandas()
    rows: List[JSON] = []
    for cell in lines:
        if cell.get("done") is True:
            continue
        base: JSON = {"ij"[k] if k < 2 else "k%d" % k: v
                      for k, v in enumerate(cell["index"])}
        base.update(cell["at"])
        base["complete"] = cell["complete"]
        if not cell["orbits"]:
            rows.append(dict(base, orbit=-1))
        for n, orbit in enumerate(cell["orbits"]):
            rows.append(dict(base, orbit=n, **_flat(orbit)))
    return pd.DataFrame(rows)


def family_frame(answer: Mapping[str, Any]) -> "pandas.DataFrame":
    """A /continue answer's branches, one row a point in the family's order
    (``branch``, ``kind``, ``value`` of the parameter, ``period``,
    ``spectral_radius``, ``stable``, ``min_margin`` by its value, ...;
    ``special`` None), then its special points, one row each with
    ``special`` their type (``grazing``, ``fold``, ...), their ``value``,
    ``precision`` and, where the answer gives it, the orbit there."""
    pd = _pandas()
    rows: List[JSON] = []
    for b, branch in enumerate(answer["branches"]):
        for p in branch["points"]:
            rows.append(dict(_flat(p), branch=b, kind=branch["kind"],
                             special=None))
        for s in branch.get("special", []):
            row = _flat(s.get("orbit") or {})
            row.update(branch=b, kind=branch["kind"], special=s["type"],
                       value=s["value"], precision=s.get("precision"))
            rows.append(row)
    return pd.DataFrame(rows)
