"""Tests of controller.program: the control program's configuration, scheduling and loop."""
