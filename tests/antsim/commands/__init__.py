"""Tests of antsim.commands."""
