"""The project's controller on an antenna over KATCP: ``antsim run ... --connect HOST:PORT``.

The scenario gives the controller its configuration (site, epoch, sources, plan, model in
use); the antenna (``antsim serve`` or any device with the requests of docs/katcp.md) gives
everything else. Its epoch must be the scenario's, or the controller's ephemeris would point
at the wrong sky; the recordings name the antenna's seed.
"""

from __future__ import annotations

import simpy
from astropy.time import Time

from controller.errors import InputError
from controller.protocol import AntennaError
from controller.wire import ConnectionLostError, KatcpAntenna

from ..scenario import Scenario

__all__ = ["connect", "parse_address"]


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6); raises InputError."""
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError("command line", "--connect", text, "expected HOST:PORT, e.g. "
                         "127.0.0.1:5025")
    return (host.strip("[]") or "127.0.0.1"), int(port)


def connect(scenario: Scenario, address: str) -> tuple[KatcpAntenna, int]:
    """A connected :class:`KatcpAntenna` (in its own simpy environment) and its seed."""
    host, port = parse_address(address)
    try:
        antenna = KatcpAntenna(host, port, simpy.Environment())
    except ConnectionLostError as err:
        raise InputError("command line", "--connect", address, str(err),
                         "start the antenna first, e.g. antsim serve SCENARIO.toml") from None
    except AntennaError as err:  # a KATCP device, but not one with docs/katcp.md's requests
        raise InputError("command line", "--connect", address,
                         f"the device there does not describe itself ({err})",
                         "connect to antsim serve, or a device with its requests") from None
    info = antenna.info
    if _epoch(info.get("epoch-utc", "")) != _epoch(scenario.epoch_utc):
        antenna.close()
        raise InputError("command line", "--connect", address,
                         f"the antenna's epoch is {info.get('epoch-utc')!r}, the scenario's "
                         f"{scenario.epoch_utc!r}",
                         "serve and run the same scenario (or one with the same epoch)")
    return antenna, int(info.get("seed", scenario.seed))


def _epoch(text: str) -> float | None:
    try:
        return round(float(Time(text, scale="utc").unix), 3)
    except ValueError:
        return None
