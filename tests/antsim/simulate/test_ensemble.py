"""antsim/simulate/ensemble.py: the executors say what they are in words."""

from __future__ import annotations

import pytest

from antsim.simulate.ensemble import PoolExecutor


@pytest.mark.parametrize(("workers", "words"), [(1, "local process pool of 1 worker"),
                                                (2, "local process pool of 2 workers")])
def test_a_pool_is_described_with_its_workers_counted(workers, words):
    with PoolExecutor(workers) as pool:
        assert pool.description == words
