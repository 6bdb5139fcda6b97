"""Tests of controller.program, a file per module."""
