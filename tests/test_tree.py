"""The tests are organised like the code: a file per module or concept under the module's
path, ``tests/<code path>/test_<module>.py``; whole commands and campaigns against a source
report in ``tests/end_to_end/``; only the tree-wide checks at the top (docs/layout.md,
"Where tests go").

Two rules are checked: no test file sits flat in ``tests/`` but the tree-wide ones, and every
module of ``antsim/`` and ``controller/`` is imported by a test (an import statement, read with
``ast``, anywhere in ``tests/``), but those :data:`NOT_IMPORTED` names with its reason.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: test files that check the whole tree, not one module: they stay at the top of tests/
TREE_WIDE = frozenset({
    "test_layout.py",  # who may import whom, across every package of antsim/ and controller/
    "test_tree.py",  # this file: where the tests go
})

#: the reason a module is run by tests that do not import it
_API = "the Python API, tested as users call it: attributes of antsim (tests/antsim/api/)"
_COMMAND = "a command's module, run through antsim.cli.main (tests/antsim/commands/, end_to_end/)"
_DEMO = "a chapter of antsim demo, run whole by tests/end_to_end/test_demo.py"
_SPLIT = "imported by no test yet; run by {} (pending a split of that file by module)"

#: modules of antsim/ and controller/ that no test imports, each with why that is acceptable.
#: A package's ``__init__`` needs no entry when a test imports one of its submodules.
NOT_IMPORTED: dict[str, str] = {
    "antsim.__main__": "python -m antsim, run as a subprocess by tests/antsim/test_cli.py",
    "antsim.schema.__main__": "python -m antsim.schema, run as a subprocess by "
                              "tests/antsim/schema/test_markdown.py",
    "antsim._version": "one line written by the build",
    "antsim.api.campaign": _API,
    "antsim.api.diagnosis": _API,
    "antsim.api.fit": _API,
    "antsim.api.fitting": _API,
    "antsim.api.planning": _API,
    "antsim.commands.diagnose": _COMMAND,
    "antsim.commands.fit": _COMMAND,
    "antsim.commands.plan": _COMMAND,
    "antsim.commands.run": _COMMAND,
    "antsim.commands.scenarios": _COMMAND,
    "antsim.commands.serve": _COMMAND,
    "antsim.commands.demo": _DEMO,
    "antsim.commands.demo.campaign": _DEMO,
    "antsim.commands.demo.closed_loop": _DEMO,
    "antsim.commands.demo.cold_start": _DEMO,
    "antsim.commands.demo.first_campaign": _DEMO,
    "antsim.commands.demo.hidden_effect": _DEMO,
    "antsim.commands.demo.story": _DEMO,
    "antsim.commands.demo.the_fit": _DEMO,
    "antsim.commands.demo.walkthrough": _DEMO,
    "antsim.figures.demo": _DEMO,
    "antsim.diagnose.candidates.dynamics": _SPLIT.format(
        "the library's tests in tests/antsim/diagnose/test_diagnose.py"),
    "antsim.diagnose.candidates.terms": _SPLIT.format(
        "the library's tests in tests/antsim/diagnose/test_diagnose.py"),
    "antsim.diagnose.request": _SPLIT.format(
        "antsim diagnose's runs in tests/antsim/diagnose/test_diagnose.py"),
    "antsim.plan.outputs": "antsim plan's files, written by runs through antsim.cli.main "
                           "(tests/antsim/plan/test_study.py, test_report.py)",
    "antsim.simulate.schedule": "the shared schedule, made through antsim.simulate.vectorized "
                                "(tests/antsim/simulate/test_vectorized.py)",
    "antsim.run.campaign": "antsim run's work, run through antsim.cli.main "
                           "(tests/antsim/run/, tests/end_to_end/test_pointing_run.py)",
    "antsim.run.report": "antsim run's report.html, run through antsim.cli.main "
                         "(tests/antsim/run/test_report_page.py)",
    "antsim.serve.app": "the server's run, started as a child process by ServerProcess "
                        "(tests/antsim/serve/test_app.py)",
    "antsim.serve.requests": "antsim serve --requests, run through antsim.cli.main "
                             "(tests/antsim/commands/test_serve.py)",
    "antsim.serve.sensors": "the device's sensors, read over KATCP "
                            "(tests/antsim/serve/test_device.py)",
    "antsim.world.weather": _SPLIT.format("the world's tests in tests/antsim/world/test_world.py"),
    "antsim.world.effects.dynamics": "its effects, made by name in a world "
                                     "(tests/antsim/world/effects/test_dynamics.py)",
    "antsim.world.effects.equatorial": "its effect, run by name in the 140-ft's scenario "
                                       "(tests/antsim/world/effects/test_effects.py)",
    "antsim.world.effects.tracking": "its effect, made by name in a world "
                                     "(tests/antsim/world/effects/test_tracking.py)",
    "controller.astro.earth": "its UTC instants and IERS values are checked through the "
                              "ephemeris against astropy "
                              "(tests/controller/astro/test_ephemeris.py)",
    "controller.program.config": "read from every scenario's [controller] tables "
                                 "(tests/antsim/test_scenario.py, tests/controller/program/)",
    "controller.program.optical": _SPLIT.format(
        "the optical campaigns in tests/end_to_end/test_bima.py"),
    "controller.program.scheduler": "its policies, run through whole campaigns "
                                    "(tests/controller/program/test_scheduler.py)",
}


def flat_test_files(root: Path) -> list[str]:
    """Test files directly in ``root/tests`` that are not tree-wide."""
    return sorted(p.name for p in (root / "tests").glob("test_*.py")
                  if p.name not in TREE_WIDE)


def code_modules(root: Path) -> set[str]:
    """Every module of ``antsim/`` and ``controller/``, dotted (a package by its own name)."""
    found = set()
    for package in ("antsim", "controller"):
        for path in (root / package).rglob("*.py"):
            parts = path.relative_to(root).with_suffix("").parts
            found.add(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return found


def imported_by_tests(root: Path) -> set[str]:
    """Every module an import statement of a file under ``root/tests`` names (``from a import
    b`` names ``a`` and, when ``b`` is a submodule, ``a.b``)."""
    names = set()
    for path in (root / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names.add(node.module)
                names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def not_imported(root: Path) -> set[str]:
    """Modules no test imports; a package counts as imported when a submodule of it is."""
    modules = code_modules(root)
    imported = imported_by_tests(root)
    missing = modules - imported
    return {m for m in missing if not any(i.startswith(m + ".") for i in imported)}


def test_no_test_file_sits_flat_in_tests():
    assert flat_test_files(ROOT) == [], (
        "move them to tests/<code path>/test_<module>.py or tests/end_to_end/ "
        "(docs/layout.md, 'Where tests go')")


def test_every_module_is_imported_by_a_test():
    missing = not_imported(ROOT) - set(NOT_IMPORTED)
    assert not missing, (f"no test imports {sorted(missing)}: add tests/<code path>/"
                         "test_<module>.py, or an entry with its reason to NOT_IMPORTED")


def test_the_allow_list_names_modules_no_test_imports():
    """An entry for a module that is gone, or that a test now imports, is stale."""
    modules = code_modules(ROOT)
    assert sorted(set(NOT_IMPORTED) - modules) == [], "entries naming no module"
    assert sorted(set(NOT_IMPORTED) - not_imported(ROOT)) == [], "entries a test now imports"


def test_a_flat_file_and_an_untested_module_are_caught(tmp_path):
    (tmp_path / "tests" / "pkg").mkdir(parents=True)
    (tmp_path / "tests" / "test_flat.py").write_text("")
    (tmp_path / "tests" / "test_layout.py").write_text("")
    for name in ("__init__", "tested", "untested"):
        (tmp_path / "controller").mkdir(exist_ok=True)
        (tmp_path / "controller" / f"{name}.py").write_text("")
    (tmp_path / "antsim").mkdir()
    (tmp_path / "antsim" / "__init__.py").write_text("")
    (tmp_path / "tests" / "pkg" / "test_tested.py").write_text(
        "import antsim\nfrom controller import tested\n")
    assert flat_test_files(tmp_path) == ["test_flat.py"]
    assert not_imported(tmp_path) == {"controller.untested"}
