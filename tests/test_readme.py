"""The README's numbers that come from long commands are checked against the commands' kept
output (``docs/results/``): each number the section quotes must be one the command printed.
The runs that are short enough are checked where they run (``tests/test_pointing_run.py``,
``test_fomalont.py``, ``test_gaincurve.py``, ``test_demo.py``). Regenerate a result file by
running the command named in its section and copying its output there.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text(encoding="utf-8")
RESULTS = REPO / "docs" / "results"


def _section(start: str, end: str) -> str:
    text = README[README.index(start):]
    return text[:text.index(end)]


def _numbers(text: str) -> list[str]:
    """Signed decimal numbers quoted with a unit (") or as counts of scans, nights, hours."""
    return re.findall(r'[-+]?\d+\.\d+(?=")|\d+(?= (?:scans|nights))|\d+\.\d+(?= h)', text)


def test_the_what_if_answer_is_the_plans_output():
    section = _section("**How many nights", "Predicted and Monte Carlo sigmas")
    output = (RESULTS / "ghigo1990_whatif.txt").read_text(encoding="utf-8")
    flat_output = " ".join(output.split())
    answer = " ".join(section[section.index("duration:"):section.index("One night")].split())
    assert answer in flat_output
    numbers = _numbers(section.replace("W4 to 6\"", ""))
    assert len(numbers) >= 12
    for number in numbers:
        assert re.search(rf"(?<![\d.]){re.escape(number.lstrip('+'))}(?![\d])", output), number
    assert "cannot separate W6/W10 (-0.99), W9/W10" in flat_output


def _recovery_table(output: str, title: str) -> dict[str, list[str]]:
    """The rows of one case of benchmarks/recovery.py's output: term -> its fields."""
    block = output[output.index(title):].split("\n\n")[0]
    return {line.split()[0]: line.replace("|", " ").split() for line in block.splitlines()[2:]}


def test_the_recovery_findings_are_the_benchmarks_output():
    output = (RESULTS / "recovery.txt").read_text(encoding="utf-8")
    section = " ".join(_section("### Are the error bars honest?",
                                "`tests/test_recovery.py` repeats").split())
    calibrated = _recovery_table(output, "ghigo1990 as calibrated (")
    cold = _recovery_table(output, "ghigo1990 without its thermal effect")
    heated = _recovery_table(output, "ghigo1990 as calibrated, heating modelled")

    def span(table, column):
        values = [float(row[column]) for row in table.values()]
        return f"{min(values):.2f}-{max(values):.2f}"

    # fields: term bias sd tpoint_sigma tpoint_spread tpoint_in3 honest_sigma honest_spread
    # mean_pull honest_in3 verdict
    assert f"spread by {span(cold, 4)} instead of 1 (without heating)" in section
    assert f"pulls spread by {span(cold, 7)} (target 0.85-1.15)" in section
    assert f"honest pulls spread by {span(heated, 7)}, with 99-100%" in section
    worst = max(cold, key=lambda n: abs(float(cold[n][8])))
    assert f"largest mean pull {abs(float(cold[worst][8])):.2f}, {worst}" in section
    worst = max(heated, key=lambda n: abs(float(heated[n][8])))
    assert f"largest mean pull {float(heated[worst][8]):.2f}, {worst}" in section
    w1, w8 = calibrated["W1"], calibrated["W8"]
    assert f"(W1 {w1[1]}\", W8 {w8[1]}\": mean pulls {w1[8]} and {w8[8]} honest sigma)" in section
    assert f"only {w1[9]} of the W1 fits and {w8[9]} of the W8 fits" in section
    assert f"({w1[5]} and {w8[5]} within 3 TPOINT sigma" in section
    shifted = sorted((n for n, row in calibrated.items() if abs(float(row[8])) >= 2 / 3),
                     key=lambda n: int(n[1:]))
    assert f"{', '.join(shifted[:-1])} and {shifted[-1]} by two thirds of an honest sigma" \
        in section


def test_the_plan_accuracy_is_the_benchmarks_output():
    output = (RESULTS / "plan_accuracy.txt").read_text(encoding="utf-8")
    ratios = {}
    for line in output.splitlines():
        m = re.match(r"^(as run|night only|day only|8 hours)\s+(W\d+)\s+(\S+\s+){3}(\S+)", line)
        if m:
            ratios[(m.group(1), m.group(2))] = float(m.group(4))
    assert len(ratios) == 40
    worst = max(ratios, key=lambda k: abs(ratios[k] - 1.0))
    section = " ".join(_section("Predicted and Monte Carlo sigmas agree", "TPOINT's sigma").split())
    assert f"agree within {100 * abs(ratios[worst] - 1.0):.0f}% for every W term" in section
    variant = worst[0].replace(" ", "-")
    assert f"the worst is the {variant} {worst[1]}, MC/F {ratios[worst]:.2f}" in section


def test_the_sunset_drift_finding_is_the_benchmarks_output():
    output = (RESULTS / "blind_fomalont.txt").read_text(encoding="utf-8")
    seeds = re.findall(r"^seed (\d+): sunset_drift .*?tau (\d+) \+- (\d+) s \(([-+]\d+)%\); "
                       r"Fit D el ([\d.]+) -> ([\d.]+)\", Fit E el ([\d.]+) -> ([\d.]+)\", "
                       r"Fit A el ([\d.]+) -> ([\d.]+)\"", output, re.M)
    named, within = re.search(r"named (\d+)/(\d+); time constant within 30% in (\d+)",
                              output).group(1, 3)
    section = " ".join(_section("Fomalont's 1' elevation change", "On real data").split())
    first = seeds[0]
    assert first[0] == "1" and len(seeds) == 16
    assert f"named `sunset_drift` on {named} of 16 seeds" in section
    assert f"time constant {first[1]} +- {first[2]} s against 5400 s ({first[3]}%)" in section
    assert f"within 30% on {within} of 16 seeds" in section
    assert all(float(s[9]) < float(s[8]) for s in seeds)  # fit A's el rms falls on every seed
    assert f"({first[8]}\" -> {first[9]}\" at seed 1)" in section
    assert f"(seed 1: E {first[6]}\" -> {first[7]}\", D {first[4]}\" -> {first[5]}\")" in section
