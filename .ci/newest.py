"""Print the installed version of every direct dependency of pyproject.toml (with the test
extra) and name those the package index has a newer version of (``pip list --outdated``).

Used by ``.ci/run`` after the README's test command in a fresh virtual environment, whose
install takes the newest versions the index offers: a dependency another package holds back
says so instead of passing as the newest.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lowest import lowest  # .ci is no package: its folder is put on sys.path


def _key(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    names = [pin.split("==")[0] for pin in lowest(root / "pyproject.toml")]
    print("ci: newest versions: " + " ".join(f"{n}=={version(n)}" for n in names))
    listing = subprocess.run([sys.executable, "-m", "pip", "list", "--outdated",
                              "--format=json"], capture_output=True, text=True, check=True)
    direct = {_key(n) for n in names}
    held = [f"{p['name']} {p['version']} (newest {p['latest_version']})"
            for p in json.loads(listing.stdout) if _key(p["name"]) in direct]
    if held:
        print("ci: held back by another package's requirements: " + ", ".join(held))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
