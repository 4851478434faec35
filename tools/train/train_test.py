#!/usr/bin/python3
"""Checks of train.py's own network (ctest TrainPipeline.RegretNetwork*): its gradient is the
loss's, and training it on a made-up choice learns the choice."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import train  # noqa: E402


def gradient_matches_finite_differences():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(7, 5))
    y = np.minimum(rng.exponential(0.5, size=(7, 4)), train.CLIP)
    net = train.RegretNetwork(6, alpha=0.1, seed=1, decision_weight=0.7, temperature=0.2)
    net.initialise(5, 4, rng)
    _, grads = net.loss_and_gradients(x, y)
    worst = 0.0
    for param, grad in zip(net.coefs_ + net.intercepts_, grads):
        for index in np.ndindex(param.shape):
            keep = param[index]
            param[index] = keep + 1e-6
            up, _ = net.loss_and_gradients(x, y)
            param[index] = keep - 1e-6
            down, _ = net.loss_and_gradients(x, y)
            param[index] = keep
            numeric = (up - down) / 2e-6
            worst = max(worst, abs(numeric - grad[index]) / max(1e-4, abs(numeric)))
    assert worst < 1e-4, "analytic and numeric gradients differ by %.3g (relative)" % worst
    return worst


def learns_a_choice():
    # Three sets; which is best depends on the first input's sign and the second's size.
    rng = np.random.default_rng(5)
    X = rng.normal(size=(1200, 3))
    best = np.where(X[:, 0] < 0, 0, np.where(np.abs(X[:, 1]) < 0.7, 1, 2))
    R = np.full((1200, 3), 1.0)
    R[np.arange(1200), best] = 0.0
    R += 0.05 * rng.random((1200, 3))
    net = train.RegretNetwork(16, alpha=0.1, seed=1, decision_weight=0.3, temperature=0.1, epochs=60)
    net.fit(X[:1000], R[:1000])
    picked = net.predict(X[1000:]).argmin(axis=1)
    share = float((picked == best[1000:]).mean())
    assert share > 0.9, "picked the right set on %.0f%% of unseen cases" % (100 * share)
    return share


if __name__ == "__main__":
    print("gradient: largest relative difference %.2g" % gradient_matches_finite_differences())
    print("choice: right on %.0f%% of unseen cases" % (100 * learns_a_choice()))
