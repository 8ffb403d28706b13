"""The one table of a run's random streams: a run's seed, expanded by `numpy.random.SeedSequence`
into independent named streams (pure numpy).

Every random source of a run (a mission, `simulate`, a campaign's run) draws from its own
stream: `stream(seed, name, *keys)` is `SeedSequence(entropy=seed, spawn_key=(STREAMS[name],
*keys))`, exactly the child that numpy's `SeedSequence(seed).spawn` would give, so the streams
are numpy's independent children of the run's seed. The `keys` index draws inside one stream
(a sonar's update n, a follower's leg, the replanner's leg and step): the stream of update n is
the n-th child of the source's stream, so a draw depends only on (seed, source, index), never
on what else ran before it.

Why explicit keys in the table (not the table position, not a hash of the name): a source keeps
its key, and its draws, when sources are added or removed; a key is never reused. Why the seed
as entropy and the source in the spawn key (not `default_rng([seed, n])` or `seed + 1`): the
seed's words are padded to the pool size before the key is mixed in, so `[s, 0]` cannot
coincide with `s`, seed s + 1 is not a shifted copy of seed s, and two sources of one run never
share a stream.

Data generators that are not a run's noise take their own fixed seeds: the synthetic seabeds
and the boulder's shape (the site itself, the same for every run) and the scoring's surface
samples (the same samples for every run, so runs are compared on the same points).
"""

from __future__ import annotations

import numpy as np

MAX_SEED = 2 ** 63 - 1  # a run's seed: an integer in [0, MAX_SEED]
SEED_RANGE = "an integer in [0, 2^63 - 1]"

# name -> spawn key. Add a source with a new key; never renumber or reuse one.
STREAMS = {
    "prior_map": 0,         # the direction of the prior map's horizontal offset
    "navigation": 1,        # the dead-reckoning error, child n: navigation update n
    "multibeam": 2,         # the multibeam's noise, child n: ping n
    "profiler": 3,          # the pencil-beam profiler's noise, child n: update n
    "dvl": 4,               # the DVL altimeter's noise, child n: measurement n
    "following": 5,         # the profile followers' RANSAC, child k: mission leg k
    "replanner": 6,         # STOMP's rollouts, child (k, i): leg k, replanning step i
    "exploration": 7,       # the view planner, child (k, i): leg k, step i (its children:
                            # 0 the random strategy, 1 the view paths' STOMP)
    "faults": 8,            # reserved: random fault times and magnitudes
    "ocean.turbulence": 9,  # the current's Ornstein-Uhlenbeck turbulence (the Ocean system)
    "ocean.waves": 10,      # the wave components' frequencies, directions and phases
    "sensors": 11,          # a configured sensor's noise, child (c, n): c the CRC-32 of its
                            # name (`sonar.sensor.stream_of`), n its update
}


def _check_keys(keys) -> tuple[int, ...]:
    out = tuple(int(k) for k in keys)
    if any(k < 0 or k != key for k, key in zip(out, keys)):
        raise ValueError(f"random stream keys must be integers >= 0, got {tuple(keys)}")
    return out


def stream(seed: int, name: str, *keys: int) -> np.random.SeedSequence:
    """The `SeedSequence` of source `name` (a key of `STREAMS`) in the run of `seed` (an
    integer in [0, MAX_SEED]), or of its child `keys` (integers >= 0)."""
    if name not in STREAMS:
        raise ValueError(f"random stream {name!r} is not in the table; allowed: "
                         f"{', '.join(STREAMS)}")
    if isinstance(seed, bool) or int(seed) != seed or not 0 <= int(seed) <= MAX_SEED:
        raise ValueError(f"seed must be {SEED_RANGE}, got {seed!r}")
    return np.random.SeedSequence(int(seed), spawn_key=(STREAMS[name], *_check_keys(keys)))


def generator(seed: int, name: str, *keys: int) -> np.random.Generator:
    """A fresh `numpy.random.Generator` on `stream(seed, name, *keys)`."""
    return np.random.default_rng(stream(seed, name, *keys))


def child(seed, *keys: int) -> np.random.SeedSequence:
    """The child `keys` of `seed`, a `SeedSequence` (or an int, taken as `SeedSequence(seed)`),
    made afresh: unlike `SeedSequence.spawn`, calling it twice gives the same child."""
    parent = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return np.random.SeedSequence(parent.entropy,
                                  spawn_key=(*parent.spawn_key, *_check_keys(keys)),
                                  pool_size=parent.pool_size)
