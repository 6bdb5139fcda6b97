"""antsim/__init__.py: the Python API's functions are attributes of ``antsim``, imported
only when first used (the command line's start-up does not load them), and importing every
subpackage (``antsim.run``, ``antsim.plan``, ...) does not hide them."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import antsim

#: every subpackage and module of antsim a user might import
SUBPACKAGES = ("run", "fit", "plan", "diagnose", "simulate", "serve", "studies", "world",
               "figures", "commands", "scenario", "cli", "options", "outdir", "progress")


def _python(code: str) -> str:
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_api_is_imported_when_first_used_and_not_before():
    printed = _python("""
        import sys
        import antsim
        print("antsim.api" in sys.modules, "matplotlib" in sys.modules)
        run = antsim.run_campaign
        print("antsim.api" in sys.modules, run.__module__)
        print(sorted(set(antsim.API) & set(dir(antsim))) == sorted(antsim.API))
        from antsim import fit_model
        print(fit_model is antsim.api.fit_model)
    """)
    assert printed.split("\n")[:4] == ["False False", "True antsim.api.campaign", "True",
                                       "True"]


def test_the_command_line_does_not_load_the_api():
    printed = _python("""
        import sys
        from antsim.cli import build_parser
        build_parser()
        print("antsim.api" in sys.modules)
    """)
    assert printed.strip() == "False"


def test_the_names_survive_importing_every_subpackage():
    printed = _python(f"""
        import importlib
        import antsim
        before = {{name: getattr(antsim, name) for name in antsim.API}}
        for sub in {SUBPACKAGES!r}:
            importlib.import_module("antsim." + sub)
        import antsim.api
        after = {{name: getattr(antsim, name) for name in antsim.API}}
        print(all(before[n] is after[n] and callable(after[n]) for n in antsim.API))
        print(sorted(set(antsim.API) & set({SUBPACKAGES!r})))
    """)
    assert printed.split("\n")[:2] == ["True", "[]"]


def test_an_unknown_name_is_still_an_attribute_error():
    import pytest

    with pytest.raises(AttributeError, match="module 'antsim' has no attribute 'run_it'"):
        antsim.run_it  # noqa: B018
