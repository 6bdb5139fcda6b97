"""Tests of antsim/api/: the Python API against the commands it shares its code with."""
