"""APReL's belief update as plain numpy, timed the way `dualrep bench belief` times ours.

    python3 benches/reference/aprel_belief.py --features 6 --answers 40 [--repeats 50]

The algorithm is APReL's `SamplingBasedBelief.create_samples` with a `SoftmaxUser` on
`Preference` data (Stanford-ILIAD/APReL, aprel/learning/belief_models.py, user_models.py,
utils/sampling_utils.py), written out without its dict and query objects:

- log-likelihood of answer j: `beta R_j - logsumexp(beta R_a, beta R_b)`, summed over the
  dataset one answer at a time as APReL does (numpy's `logaddexp` stands in for scipy's
  `logsumexp` over the pair: same value, no scipy, and if anything faster than APReL);
- uniform prior on ||theta|| <= 1 (log prior 0 or -inf);
- proposal theta + N(0, 0.05^2 I), renormalised to unit length;
- burn-in 200, thinning 20, 100 samples: 2199 proposals, started at the previous samples'
  normalised mean; accept iff log(u) < next - current.

Data: N pairs of standard-normal features answered by the deterministic oracle of a random
theta (as `dualrep bench belief`). Prints one JSON object:
{features, answers, proposals, repeats, median_ms, mean_ms, min_ms}.

`--vectorised` also evaluates the dataset's log-likelihood in one numpy expression per
proposal (a faster numpy than APReL's per-answer loop), for comparison.
"""

import argparse
import json
import statistics
import time

import numpy as np

BETA, STD, BURN_IN, THIN, SAMPLES = 1.0, 0.05, 200, 20, 100


def loglikelihood_loop(theta, slates, chosen):
    """APReL's `loglikelihood_dataset`: one softmax per answer, summed."""
    total = []
    for slate, j in zip(slates, chosen):
        rewards = BETA * (slate @ theta)
        total.append(rewards[j] - np.logaddexp(rewards[0], rewards[1]))
    return np.sum(total)


def loglikelihood_vectorised(theta, slates, chosen):
    rewards = BETA * (slates @ theta)  # N x 2
    picked = rewards[np.arange(len(chosen)), chosen]
    return np.sum(picked - np.logaddexp(rewards[:, 0], rewards[:, 1]))


def logprior(theta):
    return 0.0 if np.linalg.norm(theta) <= 1 else -np.inf


def proposal(theta):
    next_theta = theta + np.random.randn(*theta.shape) * STD
    return next_theta / np.linalg.norm(next_theta)


def create_samples(initial, loglikelihood, slates, chosen):
    """APReL's chain: burnin + thin * samples - 1 proposals, keep samples[burnin::thin]."""
    current = initial.copy()
    current_logprob = logprior(current) + loglikelihood(current, slates, chosen)
    samples = [current]
    for _ in range(BURN_IN + THIN * SAMPLES - 1):
        next_theta = proposal(current)
        next_logprob = logprior(next_theta) + loglikelihood(next_theta, slates, chosen)
        if np.log(np.random.rand()) < next_logprob - current_logprob:
            current, current_logprob = next_theta, next_logprob
        samples.append(current)
    return samples[BURN_IN::THIN]


def normalised_mean(samples):
    mean = np.mean(samples, axis=0)
    return mean / np.linalg.norm(mean)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--features", type=int, default=6)
    parser.add_argument("--answers", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--vectorised", action="store_true")
    args = parser.parse_args()

    np.random.seed(0)
    theta_true = np.random.randn(args.features)
    slates = np.random.randn(args.answers, 2, args.features)
    chosen = np.where(slates[:, 0] @ theta_true > slates[:, 1] @ theta_true, 0, 1)
    loglikelihood = loglikelihood_vectorised if args.vectorised else loglikelihood_loop

    start = np.random.randn(args.features)
    samples = create_samples(start / np.linalg.norm(start), loglikelihood, slates, chosen)
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        samples = create_samples(normalised_mean(samples), loglikelihood, slates, chosen)
        times.append((time.perf_counter() - t0) * 1e3)
    cos = float(normalised_mean(samples) @ theta_true / np.linalg.norm(theta_true))
    print(
        json.dumps(
            {
                "features": args.features,
                "answers": args.answers,
                "proposals": BURN_IN + THIN * SAMPLES - 1,
                "repeats": args.repeats,
                "median_ms": statistics.median(times),
                "mean_ms": statistics.fmean(times),
                "min_ms": min(times),
                "likelihood": "vectorised" if args.vectorised else "per_answer",
                "alignment_of_mean": cos,
            }
        )
    )


if __name__ == "__main__":
    main()
