"""The layout shows the architecture: who may import whom, and no import circles.

Every import statement of ``antsim/`` and ``controller/`` is read with ``ast`` (module level,
inside functions and under ``if TYPE_CHECKING:`` alike: a type-only import is still a
dependency a reader follows), resolved to the module it names, and checked against the
rules the package docstrings state. Implicit imports of parent packages (importing
``a.b.c`` runs ``a/__init__.py``) are not edges: they are how packages work, not a choice
of the module's author.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: the features: what a user asks for, each one command's work. They share the engines
#: (:mod:`antsim.simulate`), the figures and pages (:mod:`antsim.figures`) and everything below.
FEATURES = ("antsim.run", "antsim.fit", "antsim.serve", "antsim.plan", "antsim.diagnose",
            "antsim.studies")
#: everything that sits above the figures: the features and the command line
FEATURES_UP = ("antsim.figures", *FEATURES, "antsim.commands", "antsim.cli")
#: the teaching walk-through (``antsim demo``), a command: its chapters, one module each, and
#: the modules they share (how a chapter is told; a campaign as antsim run writes one)
DEMO = "antsim.commands.demo"
DEMO_CHAPTERS = tuple(f"{DEMO}.{name}" for name in (
    "cold_start", "first_campaign", "the_fit", "closed_loop", "hidden_effect"))
DEMO_SHARED = (f"{DEMO}.story", f"{DEMO}.campaign")

#: the Python API (notebooks), at the command line's level: it may import every feature;
#: only ``antsim``'s own lazy ``__getattr__`` imports it
API = "antsim.api"
BELOW_API = ("controller", "antsim.tomlcheck", "antsim.documents", "antsim.progress",
             "antsim.bundled", "antsim.outdir", "antsim.options", "antsim.blas",
             "antsim.world", "antsim.scenario", "antsim.simulate", *FEATURES_UP)

#: (importer prefix, forbidden prefixes, why): no module under the importer imports a module
#: under a forbidden prefix. Prefixes are dotted module names; "a.b" covers a.b and a.b.*.
RULES: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("controller", ("antsim",), "the control program never imports the simulation"),
    ("controller.errors", ("controller",), "a base module imports nothing of the program"),
    ("controller.units", ("controller",), "a base module imports nothing of the program"),
    ("controller.protocol", ("controller",), "a base module imports nothing of the program"),
    ("controller.filekind", ("controller.units", "controller.protocol", "controller.wire",
                             "controller.astro", "controller.pointing", "controller.scans",
                             "controller.program"),
     "deciding a file's kind reads text: it imports nothing of the program but its errors"),
    ("controller.wire", ("antsim", "controller.astro", "controller.pointing", "controller.scans",
                         "controller.program"),
     "the wire client is the protocol over a network: part of the controller, it imports "
     "only the base modules and never the simulation it may be talking to"),
    ("controller.astro", ("controller.pointing", "controller.scans", "controller.program",
                          "controller.protocol", "controller.wire"),
     "astronomy imports only the base modules"),
    ("controller.pointing", ("controller.scans", "controller.program", "controller.protocol",
                             "controller.wire"),
     "the pointing mathematics never imports the scan engine or the program"),
    ("controller.scans", ("controller.program", "controller.wire"),
     "the scan engine never imports the control program that runs it"),
    ("controller.program", ("controller.wire",),
     "the control program drives any antenna through the protocol, never the wire's"),
    ("antsim.tomlcheck", ("antsim.world", "antsim.simulate", "antsim.scenario",
                          "antsim.schema", *FEATURES_UP),
     "TOML checking is the base of antsim"),
    ("antsim.schema.keys", ("antsim.world", "antsim.simulate", "antsim.scenario",
                            "antsim.schema.scenario", "antsim.schema.plan",
                            "antsim.schema.markdown", *FEATURES_UP),
     "a declared setting is a base of antsim: the world's effects declare their parameters "
     "with it"),
    ("antsim.schema", ("antsim.world.world", "antsim.simulate", "antsim.scenario",
                       *FEATURES_UP),
     "the schema declares the settings of the world's parts and the controller; the "
     "scenario reader, the assembled world and all that uses them sit above it"),
    ("antsim.world", ("antsim.schema.scenario", "antsim.schema.plan",
                      "antsim.schema.markdown"),
     "the world's parts declare their settings with antsim.schema.keys; the schema's tables "
     "of them sit above the parts"),
    ("antsim.documents", ("antsim.tomlcheck", "antsim.schema", "antsim.world",
                          "antsim.simulate", "antsim.scenario", *FEATURES_UP),
     "the documents' numbers are a base of antsim: they import nothing of it"),
    ("antsim.progress", ("antsim.tomlcheck", "antsim.documents", "antsim.bundled",
                         "antsim.schema", "antsim.world", "antsim.simulate", "antsim.scenario",
                         *FEATURES_UP,
                         "controller"),
     "progress display is a base of antsim: it knows nothing of the work it shows"),
    ("antsim.bundled", ("antsim.tomlcheck", "antsim.documents", "antsim.schema",
                        "antsim.world", "antsim.simulate", "antsim.scenario", *FEATURES_UP),
     "finding the scenarios that come with antsim by name is a base of antsim: it reads no "
     "scenario"),
    ("antsim.outdir", ("antsim.schema", "antsim.world", "antsim.simulate", "antsim.scenario",
                       *FEATURES_UP,
                       "controller.astro", "controller.pointing", "controller.scans",
                       "controller.program"),
     "output directories and their lock are a base of every command that writes"),
    ("antsim.options", ("antsim.world", "antsim.simulate", "antsim.scenario", *FEATURES_UP,
                        "controller.astro", "controller.pointing", "controller.scans",
                        "controller.program"),
     "the limits of a user's counts are a base of every command and of the Python API"),
    ("antsim.world", ("antsim.simulate", *FEATURES_UP),
     "the simulated world knows nothing of what is done with it"),
    ("antsim.scenario", ("antsim.world.world", "antsim.simulate", *FEATURES_UP),
     "a scenario reads the world's parts' settings; the world is built from it, above it"),
    ("antsim.scenario", ("antsim.schema.markdown",),
     "the scenario reader reads by the schema's keys, not its reference page"),
    ("antsim.figures", ("antsim.world", "antsim.scenario", "antsim.simulate", *FEATURES,
                        "antsim.commands", "antsim.cli"),
     "figures and pages draw values, never a simulation"),
    ("antsim.simulate", FEATURES_UP,
     "the simulation engines run scenarios; the features that use them sit above them"),
    ("antsim.serve", ("antsim.figures",),
     "the server serves the world: it imports the world, scenarios and the controller only"),
    *((feature, (*(f for f in FEATURES if f != feature), "antsim.commands", "antsim.cli"),
       "a feature imports the engines and the parts below them, never another feature nor "
       "the command line: what two features share belongs below both")
      for feature in FEATURES),
    *((below, (API,), "the Python API sits at the command line's level: no feature, engine "
       "or command imports it")
      for below in BELOW_API),
    *((chapter, (*(c for c in DEMO_CHAPTERS if c != chapter), f"{DEMO}.walkthrough"),
       "a chapter of the walk-through never imports another: what it needs of an earlier "
       "one the walk-through hands it, and what two share is in the demo's shared modules")
      for chapter in DEMO_CHAPTERS),
    *((shared, (*DEMO_CHAPTERS, f"{DEMO}.walkthrough"),
       "the demo's shared modules sit below its chapters")
      for shared in DEMO_SHARED),
)
#: no module outside ``antsim.commands`` imports a command (antsim.cli finds them by name)
COMMANDS = "antsim.commands"


def _under(module: str, prefix: str) -> bool:
    return module == prefix or module.startswith(prefix + ".")


def module_files(root: Path, packages: tuple[str, ...]) -> dict[str, Path]:
    """``{dotted module name: file}`` of every module of ``packages`` under ``root``."""
    found = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join(parts)] = path
    return found


def import_graph(root: Path, packages: tuple[str, ...]) -> dict[str, dict[str, int]]:
    """``{module: {imported module: line}}`` of the modules of ``packages``: every import
    statement resolved to the module it names (``from pkg import name`` names the module
    ``pkg.name`` when there is one, else ``pkg``); imports of other packages are left out."""
    modules = module_files(root, packages)
    graph: dict[str, dict[str, int]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        edges: dict[str, int] = {}
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                targets = [f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules
                           else source for alias in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:  # a.b.function -> a.b
                    target = target.rpartition(".")[0]
                if target and target != name:
                    edges.setdefault(target, node.lineno)
        graph[name] = edges
    return graph


def rule_breaches(graph: dict[str, dict[str, int]], rules=RULES,
                  commands: str = COMMANDS) -> list[str]:
    """One line per import that breaks a rule."""
    found = []
    for module, edges in sorted(graph.items()):
        for target, line in sorted(edges.items()):
            for importer, forbidden, why in rules:
                if _under(module, importer) and any(_under(target, f) for f in forbidden):
                    found.append(f"{module} (line {line}) imports {target}: {why}")
            if _under(target, commands) and not _under(module, commands):
                found.append(f"{module} (line {line}) imports the command {target}")
    return found


def cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The import circles: strongly connected components of more than one module (Tarjan),
    each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


@pytest.fixture(scope="module")
def graph() -> dict[str, dict[str, int]]:
    return import_graph(ROOT, ("antsim", "controller"))


def test_the_graph_sees_the_imports_it_must(graph):
    """A checker that read no edges would pass everything: it must see known imports, of
    each kind (absolute, relative, inside a function)."""
    assert len(graph) > 100
    assert "controller.pointing.terms" in graph["controller.pointing.model"]  # relative
    assert "controller.units" in graph["controller.pointing.model"]  # absolute
    assert "controller.pointing.robust" in graph["controller.pointing.model"]  # in fit()
    assert "antsim.diagnose.pvalues" in graph["antsim.diagnose.candidates.base"]  # from ..


def test_imports_follow_the_layers(graph):
    assert rule_breaches(graph) == []


def test_the_demos_rules_name_its_modules(graph):
    """A rule on a module that is not there (renamed, moved) would hold nothing: the demo's
    chapters and shared modules exist, and the walk-through imports every chapter."""
    for module in (*DEMO_CHAPTERS, *DEMO_SHARED, f"{DEMO}.walkthrough"):
        assert module in graph, module
    assert set(DEMO_CHAPTERS) <= set(graph[f"{DEMO}.walkthrough"])
    assert {m for m in graph if m.startswith(f"{DEMO}.")} == \
        {*DEMO_CHAPTERS, *DEMO_SHARED, f"{DEMO}.walkthrough"}, "a new demo module: rule it"


def test_the_api_is_imported_by_antsim_alone(graph):
    """The rule on the API holds something: the API is there, imports the features the
    commands run, and only ``antsim`` (its lazy ``__getattr__``) imports it."""
    api = {m for m in graph if m == API or m.startswith(API + ".")}
    assert API in graph and f"{API}.campaign" in graph
    uses = {t for m in api for t in graph[m]}
    assert {"antsim.run.outputs", "antsim.fit.fitfile", "antsim.diagnose.request",
            "antsim.plan.outputs"} <= uses
    importers = {m for m, edges in graph.items() if m not in api and set(edges) & api}
    assert importers == {"antsim"}


def test_a_chapter_importing_another_is_caught(tmp_path):
    root = _fake_tree(tmp_path, {
        "antsim/__init__.py": "",
        "antsim/commands/__init__.py": "",
        "antsim/commands/demo/__init__.py": "",
        "antsim/commands/demo/story.py": "",
        "antsim/commands/demo/first_campaign.py": "from .story import Story\n",
        "antsim/commands/demo/the_fit.py": "from .first_campaign import tell\n",
        "antsim/commands/demo/campaign.py": "from . import the_fit\n",
    })
    assert rule_breaches(import_graph(root, ("antsim",))) == [
        f"{DEMO}.campaign (line 1) imports {DEMO}.the_fit: the demo's shared modules sit "
        "below its chapters",
        f"{DEMO}.the_fit (line 1) imports {DEMO}.first_campaign: a chapter of the "
        "walk-through never imports another: what it needs of an earlier one the walk-through "
        "hands it, and what two share is in the demo's shared modules"]


def test_no_import_circles(graph):
    assert cycles(graph) == []


def test_every_package_says_what_lives_there_and_what_it_may_import():
    for init in sorted((ROOT / "controller").rglob("__init__.py")) + sorted(
            (ROOT / "antsim").rglob("__init__.py")):
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
        rel = init.relative_to(ROOT)
        assert len(doc) > 80, f"{rel}: no docstring saying what lives there"
        if init.parent.name not in ("controller", "antsim", "effects", "candidates"):
            assert "May import" in doc or "may import" in doc, \
                f"{rel}: the docstring does not say what the package may import"


def _fake_tree(tmp_path: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return tmp_path


def test_a_bad_import_and_a_circle_are_caught(tmp_path):
    """The checker on a small tree with one import of each kind this test forbids: the
    program importing the simulation (in a function), the scan engine importing the control
    program (type-only), the command line importing a command (it must find them by name), and
    a circle through a relative import; and the two rules of the wire's pieces: the wire
    client importing the server, the server importing the run."""
    root = _fake_tree(tmp_path, {
        "controller/__init__.py": "",
        "controller/units.py": "",
        "controller/scans/__init__.py": "",
        "controller/scans/scan.py": (
            "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n"
            "    from controller.program.config import X\n"
        ),
        "controller/program/__init__.py": "",
        "controller/program/config.py": "def f():\n    import antsim.world\n",
        "antsim/__init__.py": "",
        "antsim/world/__init__.py": "",
        "antsim/world/a.py": "from . import b\n",
        "antsim/world/b.py": "from .a import thing\n",
        "controller/wire.py": "import antsim.serve.device\n",
        "antsim/serve/__init__.py": "",
        "antsim/serve/device.py": "from antsim.run.runner import UtcLabeller\n",
        "antsim/run/__init__.py": "",
        "antsim/run/runner.py": "",
        "antsim/commands/__init__.py": "",
        "antsim/commands/run.py": "",
        "antsim/cli.py": "from antsim.commands import run\n",
    })
    graph = import_graph(root, ("antsim", "controller"))
    breaches = rule_breaches(graph)
    assert any(b.startswith("controller.program.config (line 2) imports antsim.world")
               for b in breaches)
    assert any(b.startswith("controller.scans.scan (line 3) imports controller.program.config")
               for b in breaches)
    assert "antsim.cli (line 1) imports the command antsim.commands.run" in breaches
    # the wire client importing the server breaks two rules: the controller's and its own
    assert [b for b in breaches if b.startswith("controller.wire (line 1)")] == [
        f"controller.wire (line 1) imports antsim.serve.device: {why}" for why in (
            "the control program never imports the simulation",
            "the wire client is the protocol over a network: part of the controller, it "
            "imports only the base modules and never the simulation it may be talking to")]
    assert any(b.startswith("antsim.serve.device (line 1) imports antsim.run.runner")
               for b in breaches)
    assert len(breaches) == 6
    assert cycles(graph) == [["antsim.world.a", "antsim.world.b"]]


#: where an import inside a function is the right place, and why. Commands import their
#: feature when they run (the command line starts without loading every feature).
IMPORTS_INSIDE: dict[tuple[str, str], str] = {
    ("antsim/__init__.py", "__getattr__"):
        "the Python API is imported when first used, so that the command line starts light",
    ("antsim/cli.py", "check_figure_backend"):
        "matplotlib is imported with MPLBACKEND unset, to check the variable before use",
    ("antsim/outdir.py", "__enter__"):
        "fcntl exists on POSIX only; without it the lock is a plain file",
    ("antsim/simulate/ensemble.py", "__init__"): "Dask is optional (pip install antsim[dask])",
    ("antsim/simulate/ensemble.py", "as_completed"): "Dask is optional",
    ("controller/astro/site.py", "earth_location"):
        "astropy.coordinates takes large parts of a second: controller.astro stays light for "
        "the command line, and only exact astropy transforms need it",
    ("controller/pointing/model.py", "fit"):
        "the fitter brings scipy (0.3 s): importing a model, as the command line does, "
        "stays cheap",
    ("controller/astro/ephemeris.py", "icrs_radec_rad"):
        "astropy.coordinates, as for earth_location: only a catalogue's first positions need it",
}


def imports_inside_functions(root: Path) -> list[str]:
    """Each import made inside a function outside ``antsim/commands/``, as
    'path:line in function', but for :data:`IMPORTS_INSIDE`'s."""
    found = []
    for top in ("antsim", "controller"):
        for path in sorted((root / top).rglob("*.py")):
            rel = path.relative_to(root).as_posix()
            if rel.startswith("antsim/commands/"):
                continue
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for func in ast.walk(tree):
                if not isinstance(func, ast.FunctionDef | ast.AsyncFunctionDef):
                    continue
                if (rel, func.name) in IMPORTS_INSIDE:
                    continue
                found += [f"{rel}:{node.lineno} in {func.name}" for node in ast.walk(func)
                          if isinstance(node, ast.Import | ast.ImportFrom)]
    return sorted(set(found))


def test_modules_import_at_the_top():
    """A reader sees what a module depends on at its top: imports inside functions only in
    the commands and where :data:`IMPORTS_INSIDE` says why."""
    assert imports_inside_functions(ROOT) == []


def test_an_import_inside_a_function_is_caught(tmp_path):
    root = _fake_tree(tmp_path, {
        "controller/__init__.py": "",
        "controller/units.py": "def f():\n    import math\n    return math.pi\n",
        "antsim/__init__.py": "def __getattr__(name):\n    from . import api\n",
        "antsim/commands/__init__.py": "",
        "antsim/commands/run.py": "def main():\n    import antsim.world\n",
    })
    assert imports_inside_functions(root) == ["controller/units.py:2 in f"]
