"""Tests of antsim.schema: the declared keys of scenario and plan files."""
