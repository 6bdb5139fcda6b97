"""The scheduler's constraints (controller.program.constraints): the spread policy's history."""

from __future__ import annotations

import numpy as np


def test_recent_history_is_the_same_as_scanning_it_all():
    """The spread policy's memory is bisected and each source's last time kept (a month's
    history made the scans quadratic); they must give exactly what scanning the history
    gives, boundaries included."""
    from controller.program.constraints import History

    rng = np.random.default_rng(5)
    memory_s = 6 * 3600.0
    history = History()
    for t, name in zip(np.cumsum(rng.choice([0.0, 250.0, 0.1, memory_s], size=400)),
                       rng.choice(["a", "b", "c"], size=400, p=[0.6, 0.39, 0.01]), strict=True):
        history.add(float(t), str(name), 0.0, 45.0)
    # now at, just after and between the observation times, so t_s - t == memory_s occurs
    for now in [t + memory_s for t in history.t_s[::7]] + [0.0, history.t_s[-1] + 1e6]:
        plain = [i for i, t in enumerate(history.t_s) if now - t <= memory_s]
        assert list(history.recent(now, memory_s)) == plain
    history.add(history.t_s[-1] - 10.0, "b", 0.0, 45.0)  # out of order: no bisection
    now = history.t_s[-1] + memory_s
    assert not history.in_time_order
    assert list(history.recent(now, memory_s)) == [
        i for i, t in enumerate(history.t_s) if now - t <= memory_s]
    # each source's last time is that of its latest entry (not the largest time), also in
    # a history made from lists
    copy = History(list(history.t_s), list(history.names), list(history.az_deg),
                   list(history.el_deg))
    assert not copy.in_time_order
    for name in ("a", "b", "c", "never"):
        latest = [t for t, n in zip(history.t_s, history.names, strict=True) if n == name]
        assert history.last_time(name) == copy.last_time(name) == (
            latest[-1] if latest else None)
