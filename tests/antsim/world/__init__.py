"""Tests of antsim.world."""
