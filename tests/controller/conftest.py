"""Fixtures of the controller's tests: antsim serve's virtual-clock server, for the KATCP
client's tests (tests/controller/test_wire.py)."""

from tests.antsim.serve.conftest import server, short_path  # noqa: F401 (the fixtures)
