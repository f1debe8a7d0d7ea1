"""export.chunk_spans: how one recording's samples are cut into the pool's chunks (the last ones halving, so that the
workers end close together), for every count and chunk size."""
from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from platform_tools.dataset.export import chunk_spans


@given(n=st.integers(0, 5000), size=st.integers(1, 64))
def test_spans_cover_every_sample_once_in_order(n, size):
    spans = chunk_spans(n, size)
    assert [s for a, b in spans for s in range(a, b)] == list(range(n))
    assert all(1 <= b - a <= size for a, b in spans)


@given(n=st.integers(1, 5000), size=st.integers(1, 64))
def test_after_the_first_chunk_the_sizes_never_grow_and_the_last_is_one_sample(n, size):
    sizes = [b - a for a, b in chunk_spans(n, size)]
    assert all(x >= y for x, y in zip(sizes[1:], sizes[2:]))
    assert sizes[-1] == 1


@given(n=st.integers(0, 5000), size=st.integers(1, 64))
def test_no_more_chunks_than_uniform_cutting_and_its_halvings_add(n, size):
    """Cutting the tail costs at most two chunks per halving of ``size`` (the per-chunk overhead stays bounded)."""
    uniform = -(-n // size)
    assert len(chunk_spans(n, size)) <= uniform + 2 * size.bit_length()


def test_the_sixty_one_samples_of_a_minute_at_one_hz():
    assert [b - a for a, b in chunk_spans(61, 8)] == [7, 8, 8, 8, 8, 8, 4, 4, 2, 2, 1, 1]
    assert [b - a for a, b in chunk_spans(3, 8)] == [1, 1, 1]
    assert [b - a for a, b in chunk_spans(5, 1)] == [1, 1, 1, 1, 1]
