"""The package's build backend (PEP 517 and PEP 660), standard library only,
so that ``pip install ./python`` builds offline: pip's isolated build
environment then needs nothing from an index (setuptools would be fetched
into it).  The wheel holds the ``stickslip`` package as it is, its metadata
made from pyproject.toml's [project] table; the sdist holds this directory
but its tests.
"""

from __future__ import annotations

import base64
import hashlib
import io
import os
import sys
import tarfile
import zipfile
from typing import Any, Dict, List, Mapping, Optional, Tuple

if sys.version_info >= (3, 11):
    import tomllib
else:  # pyproject.toml requires tomli there
    import tomli as tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = "stickslip"


def _project() -> Dict[str, Any]:
    with open(os.path.join(HERE, "pyproject.toml"), "rb") as f:
        project: Dict[str, Any] = tomllib.load(f)["project"]
    return project


def _metadata(p: Mapping[str, Any]) -> str:
    lines = ["Metadata-Version: 2.1", "Name: " + p["name"],
             "Version: " + p["version"], "Summary: " + p["description"],
             "License: " + p["license"]["text"],
             "Requires-Python: " + p["requires-python"]]
    lines += ["Requires-Dist: " + d for d in p.get("dependencies", [])]
    for extra, deps in p.get("optional-dependencies", {}).items():
        lines.append("Provides-Extra: " + extra)
        lines += ['Requires-Dist: %s; extra == "%s"' % (d, extra)
                  for d in deps]
    return "\n".join(lines) + "\n"


def _dist_info(p: Mapping[str, Any]) -> List[Tuple[str, str]]:
    """The .dist-info's files but RECORD: (name, text)."""
    name = "%s-%s.dist-info/" % (p["name"], p["version"])
    scripts = "".join("%s = %s\n" % kv for kv in p.get("scripts", {}).items())
    return [(name + "METADATA", _metadata(p)),
            (name + "WHEEL", "Wheel-Version: 1.0\nGenerator: stickslip_build"
             "\nRoot-Is-Purelib: true\nTag: py3-none-any\n"),
            (name + "entry_points.txt", "[console_scripts]\n" + scripts)]


def _wheel(directory: str, files: List[Tuple[str, bytes]]) -> str:
    """Write a wheel of ``files`` (its RECORD added) into ``directory``;
    its file name."""
    p = _project()
    files = files + [(n, t.encode()) for n, t in _dist_info(p)]
    record = "%s-%s.dist-info/RECORD" % (p["name"], p["version"])
    lines = []
    for name, data in files:
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest())
        lines.append("%s,sha256=%s,%d" % (name, digest.rstrip(b"=").decode(),
                                          len(data)))
    files.append((record, ("\n".join(lines + [record + ",,"]) + "\n")
                  .encode()))
    wheel = "%s-%s-py3-none-any.whl" % (p["name"], p["version"])
    with zipfile.ZipFile(os.path.join(directory, wheel), "w",
                         zipfile.ZIP_DEFLATED) as z:
        for name, data in files:
            z.writestr(zipfile.ZipInfo(name, (1980, 1, 1, 0, 0, 0)), data)
    return wheel


def _package() -> List[Tuple[str, bytes]]:
    out = []
    for name in sorted(os.listdir(os.path.join(HERE, PACKAGE))):
        if name.endswith(".py") or name == "py.typed":
            with open(os.path.join(HERE, PACKAGE, name), "rb") as f:
                out.append((PACKAGE + "/" + name, f.read()))
    return out


def get_requires_for_build_wheel(
        config_settings: Optional[Mapping[str, Any]] = None) -> List[str]:
    return []


get_requires_for_build_sdist = get_requires_for_build_wheel
get_requires_for_build_editable = get_requires_for_build_wheel


def build_wheel(wheel_directory: str,
                config_settings: Optional[Mapping[str, Any]] = None,
                metadata_directory: Optional[str] = None) -> str:
    return _wheel(wheel_directory, _package())


def build_editable(wheel_directory: str,
                   config_settings: Optional[Mapping[str, Any]] = None,
                   metadata_directory: Optional[str] = None) -> str:
    """A wheel whose .pth puts this directory on sys.path."""
    return _wheel(wheel_directory, [(PACKAGE + ".pth",
                                     (HERE + "\n").encode())])


def build_sdist(sdist_directory: str,
                config_settings: Optional[Mapping[str, Any]] = None) -> str:
    p = _project()
    base = "%s-%s" % (p["name"], p["version"])
    names = ["pyproject.toml", os.path.basename(__file__)] + \
        [n for n, _ in _package()]
    with tarfile.open(os.path.join(sdist_directory, base + ".tar.gz"),
                      "w:gz", format=tarfile.PAX_FORMAT) as tar:
        for name in names:
            tar.add(os.path.join(HERE, name), base + "/" + name)
        info = tarfile.TarInfo(base + "/PKG-INFO")
        data = _metadata(p).encode()
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))
    return base + ".tar.gz"
