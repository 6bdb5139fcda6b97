"""Scenarios and plans come with antsim and are run by name (antsim.bundled, antsim scenarios);
the wheel carries them, and an installed wheel runs them from an empty directory."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from antsim.bundled import catalogue, find, names, scenarios_dir, shown
from antsim.cli import main
from antsim.plan.planfile import load_plan
from controller.errors import InputError

REPO = Path(__file__).resolve().parents[2]
SOURCE = REPO / "scenarios"


def test_a_source_tree_uses_its_top_level_scenarios():
    assert scenarios_dir() == SOURCE
    assert names() == sorted(p.stem for p in SOURCE.glob("*.toml"))
    assert names("plan") == sorted(p.stem for p in (SOURCE / "plans").glob("*.toml"))
    assert "ghigo1990" in names() and "ghigo1990_whatif" in names("plan")


def test_a_name_a_name_with_toml_and_a_path_find_the_file(tmp_path, monkeypatch):
    assert find("ghigo1990") == SOURCE / "ghigo1990.toml"
    assert find("ghigo1990.toml") == SOURCE / "ghigo1990.toml"
    assert find("ghigo1990_whatif", "plan") == SOURCE / "plans" / "ghigo1990_whatif.toml"
    own = tmp_path / "ghigo1990.toml"
    own.write_text("name = 'mine'\n", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert find("ghigo1990.toml") == Path("ghigo1990.toml")  # a file that exists wins
    assert find(str(own)) == own
    assert shown(SOURCE / "ghigo1990.toml") == "ghigo1990"
    assert shown(own) == str(own)


def test_an_unknown_name_is_one_line_with_the_valid_names():
    with pytest.raises(InputError) as err:
        find("ghigo1991")
    line = str(err.value)
    assert line.startswith("command line: SCENARIO = 'ghigo1991': neither a file nor the name")
    assert " ".join(names()) in line and "\n" not in line
    with pytest.raises(InputError, match="no such scenario file; the scenario that comes with "
                                         "antsim is named ghigo1990"):
        find("elsewhere/ghigo1990.toml")
    with pytest.raises(InputError, match=r"^/no/such/dir/x.toml: SCENARIO = "):
        find("/no/such/dir/x.toml")
    with pytest.raises(InputError, match="plans that come with antsim: crane1981_days "
                                         "ghigo1990_sensors_whatif ghigo1990_whatif"):
        find("whatif", "plan")


@pytest.mark.parametrize("argv", [["run", "ghigo1991", "--out", "x"], ["plan", "nosuch"],
                                  ["diagnose", "r.ecsv", "--scenario", "nosuch"],
                                  ["blindtest", "--scenario", "nosuch"],
                                  ["demo", "--scenario", "nosuch"], ["serve", "nosuch"],
                                  ["scenarios", "nosuch"]])
def test_every_command_refuses_an_unknown_name_in_one_line(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and ("'nosuch'" in err or "'ghigo1991'" in err)
    assert "ghigo1990" in err  # the valid names are listed
    assert not list(tmp_path.iterdir())  # nothing was started


def test_antsim_scenarios_lists_each_with_its_telescope_and_description(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for kind in ("scenario", "plan"):
        entries = catalogue(kind)
        assert [e.name for e in entries] == names(kind)
        for e in entries:
            (line,) = [x for x in out.splitlines() if x.split()[:1] == [e.name]]
            assert e.telescope and e.telescope in line and e.description in line
    assert "NRAO Green Bank 45-ft" in next(x for x in out.splitlines()
                                           if x.split()[:1] == ["ghigo1990_whatif"])
    assert main(["scenarios", "wright1992_bima_ant5"]) == 0
    assert capsys.readouterr().out == (SOURCE / "wright1992_bima_ant5.toml").read_text()


def test_a_plan_names_its_scenario_by_name_or_by_a_path(tmp_path):
    text = ('name = "p"\nscenario = "{}"\nmembers = 2\n[[variants]]\nname = "a"\n'
            '[[variants]]\nname = "b"\nscenario = "{}"\n')
    (tmp_path / "copy.toml").write_text((SOURCE / "fomalont1973_s.toml").read_text())
    plan = tmp_path / "plan.toml"
    plan.write_text(text.format("ghigo1990", "copy.toml"), encoding="utf-8")
    loaded = load_plan(plan)
    assert [s.name for s in loaded.scenarios] == ["ghigo1990", "fomalont1973_s"]
    plan.write_text(text.format("ghigo1990", "nowhere.toml"), encoding="utf-8")
    with pytest.raises(InputError, match=r"variants\[1\]\.scenario = 'nowhere.toml': no such "
                                         r"scenario file; paths are relative to "):
        load_plan(plan)


def test_the_wheel_carries_every_scenario_and_plan(built_wheel):
    inside = set(zipfile.ZipFile(built_wheel).namelist())
    for path in [*SOURCE.glob("*.toml"), *SOURCE.glob("plans/*.toml")]:
        name = f"antsim/scenarios/{path.relative_to(SOURCE).as_posix()}"
        assert name in inside, name
        assert zipfile.ZipFile(built_wheel).read(name) == path.read_bytes()


def test_an_installed_wheel_runs_scenarios_by_name_from_an_empty_directory(installed,
                                                                            tmp_path):
    listing = installed.run("antsim scenarios", cwd=tmp_path)
    assert listing.returncode == 0, listing.stderr
    where = listing.stdout.strip().splitlines()[-1]
    assert str(installed.venv) in where and str(REPO) not in where  # the wheel's own copy
    run = installed.run("antsim run wright1992_bima_ant5 --out runs/bima --no-report",
                        cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "runs" / "bima" / "model.dat").is_file()
    bad = installed.run("antsim plan ghigo1991", cwd=tmp_path)
    assert bad.returncode == 2 and "plans that come with antsim" in bad.stderr
