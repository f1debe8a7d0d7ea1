"""indexscan.parts: the index's chunks cut into runs for the pool's workers: contiguous, in file order, every chunk
once, and (8 runs or more) the last four smaller (half, half, a quarter, a quarter) so that the workers end close
together."""
from __future__ import annotations

from dataclasses import dataclass

from hypothesis import given
from hypothesis import strategies as st

from platform_tools.dataset.indexscan import parts


@dataclass(frozen=True)
class Chunk:
    chunk_start_offset: int
    uncompressed_size: int


@given(sizes=st.lists(st.integers(0, 3_000_000), max_size=300), n=st.integers(1, 40), seed=st.randoms())
def test_runs_are_contiguous_in_file_order_and_hold_every_chunk_once(sizes, n, seed):
    chunks = [Chunk(i * 10, s) for i, s in enumerate(sizes)]
    shuffled = list(chunks)
    seed.shuffle(shuffled)
    runs = parts(shuffled, n)
    assert [c for r in runs for c in r] == chunks
    assert len(runs) <= n and all(runs)


def test_the_last_four_runs_halve():
    chunks = [Chunk(i, 1000) for i in range(5500)]
    sizes = [len(r) for r in parts(chunks, 8)]
    assert sizes == [1000, 1000, 1000, 1000, 500, 500, 250, 250]
    assert [len(r) for r in parts(chunks[:600], 6)] == [100] * 6          # fewer runs: all alike
