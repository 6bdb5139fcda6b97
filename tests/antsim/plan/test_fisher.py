"""The predicted error of every fitted term (antsim.plan.fisher) against Monte Carlo."""

from __future__ import annotations

import math

import numpy as np

from antsim.simulate.vectorized import (
    member_seed,
)


def test_predicted_sigma_agrees_with_monte_carlo(smooth_engine):
    """The reduced version of benchmarks/plan_accuracy.py: 96 members of the 3-hour run.
    Tolerance from the sampling error of a standard deviation, 1/sqrt(2(N-1)) = 7.3%: three
    of it per term plus 5% for the prediction's own approximations (linear response, Gaussian
    gusts, the rejections simulated on 64 draws of Gaussian noise); the mean ratio over the
    terms within 5% + 2 of it. This is a daytime run of 33 observations for ten terms: the
    robust fit rejects about one of them (0.90 per member over 192 members), among the
    heating's large deterministic residuals, and that is half of W5's variance; the
    truncated-normal model of the rejections that the simulation replaced predicted 0.30
    and W5's sigma 1.41 times too small."""
    from antsim.plan.fisher import noise_model, predict
    from antsim.simulate.vectorized import MemberResults

    scenario, engine = smooth_engine
    n = 96
    noise = noise_model(engine, 7, n_thermal=128)
    truth = np.array([scenario.truth_model.as_dict().get(t, 0.0) for t in engine.terms])
    pred = predict(engine.shared, engine.terms, noise, truth=truth)
    parts = []
    for start in range(0, n, 48):
        members = list(range(start, start + 48))
        res, _ = engine.run_block(members, [member_seed(7, m) for m in members])
        parts.append(res)
    res = MemberResults.concat(parts)
    values = res.values[~res.failed]
    assert len(values) >= n - 3
    ratio = values.std(axis=0, ddof=1) / pred.sigma_arcsec
    err = 1.0 / math.sqrt(2 * (len(values) - 1))
    assert np.all(np.abs(ratio - 1.0) <= 0.05 + 3 * err), ratio
    assert abs(np.exp(np.mean(np.log(ratio))) - 1.0) <= 0.05 + 2 * err
    # the Sky RMS of the used observations, predicted and simulated, within 10%
    assert abs(np.mean(res.sky_rms) / pred.sky_rms_arcsec - 1.0) < 0.10
    # observations rejected per member, predicted and simulated: ~0.9 +- 0.9 per member, so
    # the mean of 96 is good to 0.1 and the prediction's 64 draws to 0.12; 0.5 is 3 of both
    rejected = pred.n_scans - res.n_used[~res.failed]
    assert abs(np.mean(rejected) - pred.n_rejected) <= 0.5, (np.mean(rejected), pred.n_rejected)
