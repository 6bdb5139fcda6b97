"""The request list that ``antsim serve --requests`` prints: every request the device
serves, with its arguments, its reply and its meaning, read from the device's own handlers
(aiokatcp's registry and the handlers' docstrings), so that the list is what the server
answers, and an installed antsim carries it without the repository's docs/katcp.md."""

from __future__ import annotations

import inspect

from .device import AntennaDevice

#: what every client needs before the list (docs/katcp.md, "Conventions", says more)
CONVENTIONS = """\
antsim serve: the simulated antenna as a KATCP v5 device (aiokatcp).
Conventions:
  time       the antenna's clock, seconds since the scenario's epoch (?antenna gives the
             epoch, ?clock the UTC); sensor timestamps are the simulated UTC
  angles     encoder degrees; azimuth North = 0, East = 90, on the cable wrap; elevation
             above the horizon (an equatorial mount: hour angle, positive West, and
             declination)
  offsets    ?offset DAZ DEL adds encoder degrees to the program track; a cross-elevation
             step x on the sky is an azimuth offset x / cos E
  pointing   offsets measured (the camera's) are the correction to apply: indicated minus true
  powers     kelvin, per receiver channel in ?channels' order
  weather    air temperature C, pressure hPa, relative humidity 0..1, wind m/s
One client commands (the first to send a command, until it disconnects or sends ?release);
every client may read. Every command's reply starts with the clock after it. A bad argument
gets a failure reply naming it.
"""


def request_list() -> str:
    """The conventions, then each request: its name, whether it commands or reads, and its
    docstring (the arguments, the reply after ``ok`` and what it does)."""
    kinds = {"command": "command", "reading": "reading",
             "command-with-args": "reading without arguments, command with them"}
    ours, theirs = [], []
    for name, handler in AntennaDevice._request_handlers.items():
        doc = inspect.cleandoc(handler.__doc__ or "").strip()
        kind = getattr(handler, "antsim_kind", None)
        if kind is None:
            theirs.append(f"?{name:<24}{doc.splitlines()[0] if doc else ''}")
            continue
        lines = doc.splitlines()
        body = "".join(f"\n    {line}" if line else "\n" for line in lines[1:])
        ours.append(f"?{name} ({kinds[kind]})\n    {lines[0]}{body}")
    return (CONVENTIONS + "\nRequests:\n\n" + "\n\n".join(ours)
            + "\n\naiokatcp's own requests:\n" + "\n".join(theirs) + "\n")
