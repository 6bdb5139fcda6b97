"""Tests of antsim.diagnose.candidates, a file per module."""
