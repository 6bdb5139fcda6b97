"""Tests of controller.pointing, a file per module."""
