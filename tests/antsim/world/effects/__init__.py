"""Tests of antsim.world.effects: the physical effects, one file per module."""
