"""ScanLog's history: versions beyond the current chunk are frozen offset arrays, not objects,
and `since` still tells a version of the past from one of another branch."""

import gc

import numpy as np

from drake_auv.mapping.scan_log import CHUNK_BATCHES, ScanBatch, ScanLog


def _batch(k: int) -> ScanBatch:
    d = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return ScanBatch.make(0.1 * k, "multibeam", [k, 0.0, 0.0], d, [1.0 + k, np.nan], 20.0)


def _grow(log: ScanLog, n: int, first: int = 0, keep=None) -> ScanLog:
    for k in range(first, first + n):
        log = log.append(_batch(k))
        if keep is not None:
            keep.append(log)
    return log


def _times(batches) -> list[float]:
    return [b.time for b in batches]


def test_since_reads_exactly_the_batches_after_any_past_version_across_chunks():
    versions = []
    head = _grow(ScanLog(), 3 * CHUNK_BATCHES + 17, keep=versions)
    assert head.count == len(versions) and head.returns == head.count
    every = _times(head.iter_batches())
    np.testing.assert_allclose(every, 0.1 * np.arange(head.count))
    for k in (0, 1, CHUNK_BATCHES - 1, CHUNK_BATCHES, CHUNK_BATCHES + 1, 2 * CHUNK_BATCHES,
              3 * CHUNK_BATCHES + 16):
        older = versions[k - 1] if k else None
        assert _times(head.since(older)) == every[k:], k
    assert head.since(head) == []


def test_since_refuses_a_version_of_another_branch_or_store():
    trunk = _grow(ScanLog(), CHUNK_BATCHES + 5)
    left = _grow(trunk, 2 * CHUNK_BATCHES, first=10_000)
    right = _grow(trunk, 2 * CHUNK_BATCHES, first=20_000)
    assert left.store is right.store  # one shared file, interleaved records
    assert right.since(left) is None and left.since(right) is None
    # the same count on the other branch, on either side of a chunk boundary
    for n in (1, CHUNK_BATCHES - 5, CHUNK_BATCHES - 4, CHUNK_BATCHES):
        other = _grow(trunk, n, first=30_000)
        assert left.since(other) is None, n
    assert _times(left.since(trunk)) == _times(left.iter_batches())[trunk.count:]
    assert _grow(ScanLog(), 3).since(_grow(ScanLog(), 2)) is None  # another store


def test_only_the_current_chunk_of_versions_stays_alive():
    head = _grow(ScanLog(), 5 * CHUNK_BATCHES + 3)
    gc.collect()
    alive = sum(isinstance(o, ScanLog) for o in gc.get_objects())
    # a version per batch would keep 5,123 of them; the chunks keep 8 B per batch instead
    assert alive <= CHUNK_BATCHES + 1
    chunks, chunk = 0, head.chunk
    while chunk is not None:
        assert not chunk.offsets.flags.writeable and len(chunk.offsets) == CHUNK_BATCHES
        chunks, chunk = chunks + 1, chunk.parent
    assert chunks == 5 and head.parent.parent.parent.parent is None  # three since the boundary
    assert len(head.batches()) == head.count
