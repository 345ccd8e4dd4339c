"""The arrays and frames hold exactly the JSON they come from."""

from __future__ import annotations

import base64
import math

import pytest

import stickslip
from conftest import PAPER

np = pytest.importorskip("numpy")
pd = pytest.importorskip("pandas")
from stickslip import arrays  # noqa: E402


def test_samples(client: stickslip.Client) -> None:
    orbit = client.orbit(params=PAPER, kind="overshoot", samples={
        "tolerance": 1e-3, "fields": ["t", "x1", "x2", "v1", "v2", "mode",
                                      "force", "F1", "F2"]})["orbits"][0]
    cols = arrays.samples(orbit)
    assert set(cols) == set(orbit["samples"])
    for k, v in orbit["samples"].items():
        assert cols[k].tolist() == v, k
    assert cols["t"].dtype == float and len(cols["mode"]) == len(cols["t"])
    sim = client.simulate(params=PAPER, initial=orbit["x0"], t_end=20,
                          samples={"n": 40})
    frame = arrays.samples_frame(sim)
    assert list(frame["x2"]) == sim["samples"]["x2"]
    assert list(frame["mode"]) == sim["samples"]["mode"]


def test_basins(client: stickslip.Client) -> None:
    ans = client.basins(params=PAPER, state={"v1": 0, "v2": 1}, axes=[
        {"variable": "x1", "from": -2, "to": 4, "n": 7},
        {"variable": "x2", "from": 0, "to": 8, "n": 5}])
    b = arrays.basins(ans)
    raw = base64.b64decode(ans["labels"]["data"])
    assert b.labels.shape == (7, 5)
    for i in range(7):
        for j in range(5):
            assert b.labels[i, j] == raw[i * 5 + j]
    assert b.attractors == ans["attractors"]
    for a in ans["attractors"]:
        assert (b.labels == a["label"]).sum() == a["cells"]
    assert b.axes[0][0] == "x1" and b.axes[0][1].tolist() == \
        [-2, -1, 0, 1, 2, 3, 4]
    assert b.unresolved == 255 and b.perpetual_slip == 254


def test_map_frame(client: stickslip.Client) -> None:
    body = {"params": PAPER, "axes": [
        {"parameter": "ur", "from": 0.3, "to": 0.7, "n": 3},
        {"parameter": "chi", "from": 0.1, "to": 0.3, "n": 2}]}
    cells = client.map(body).gather()
    f = arrays.map_frame(cells)
    assert len(f) == sum(max(1, len(c["orbits"])) for c in cells)
    k = 0
    for c in cells:
        for n, o in enumerate(c["orbits"] or [None]):
            row = f.iloc[k]
            k += 1
            assert (row["i"], row["j"]) == tuple(c["index"])
            assert row["ur"] == c["at"]["ur"] and row["chi"] == c["at"]["chi"]
            if o is None:
                assert row["orbit"] == -1
                continue
            assert row["orbit"] == n and row["period"] == o["period"]
            assert row["kind"] == o["kind"] and row["stable"] == o["stable"]
            assert row["min_margin"] == o["min_margin"]["value"]
            assert list(row["durations"]) == o["durations"]


def test_family_frame(client: stickslip.Client) -> None:
    ans = client.continuation(params=PAPER, parameter="ur", range=[0.3, 1.5],
                              guess={"durations": [4.4975, 2.7227, 3.0513]})
    f = arrays.family_frame(ans)
    pts = f[f["special"].isna()]
    sp = f[f["special"].notna()]
    branch = ans["branches"][0]
    assert list(pts["value"]) == [p["value"] for p in branch["points"]]
    assert list(pts["period"]) == [p["period"] for p in branch["points"]]
    assert list(pts["min_margin"]) == \
        [p["min_margin"]["value"] for p in branch["points"]]
    assert list(sp["special"]) == [s["type"] for s in branch["special"]]
    assert list(sp["value"]) == [s["value"] for s in branch["special"]]
    assert "grazing" in list(sp["special"])
    assert not any(math.isnan(v) for v in sp["period"])
