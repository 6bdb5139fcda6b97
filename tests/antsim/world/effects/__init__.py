"""Tests of antsim.world.effects."""
