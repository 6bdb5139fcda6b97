"""Print pip constraints pinning every direct dependency of pyproject.toml (with the test
extra) to the lowest version it allows: ``numpy>=1.26`` -> ``numpy==1.26``.

Used by ``.ci/minimum`` (the suite with the oldest versions the project claims to support).
A requirement without a lower bound is an error: an unbounded dependency cannot be tested at
its minimum.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?\s*>=\s*([^,;\s]+)\s*$")


def lowest(pyproject: Path, extras: tuple[str, ...] = ("test",)) -> list[str]:
    project = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]
    requirements = list(project["dependencies"])
    for extra in extras:
        requirements += project["optional-dependencies"][extra]
    pins = []
    for requirement in requirements:
        match = REQUIREMENT.match(requirement)
        if match is None:
            raise SystemExit(f"{pyproject}: {requirement!r} has no single lower bound (>=)")
        name, _extra, version = match.groups()  # a constraint names no extras
        pins.append(f"{name}=={version}")
    return pins


if __name__ == "__main__":
    root = Path(__file__).resolve().parents[1]
    sys.stdout.write("\n".join(lowest(root / "pyproject.toml")) + "\n")
