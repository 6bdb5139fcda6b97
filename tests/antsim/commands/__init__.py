"""Tests of antsim/commands."""
