"""Exact grouping of equal integer keys by open hash tables, without sorting.

The world-mesh path welds vertices (equal grid cells) and tests winding (repeated
directed edges) on arrays of tens of thousands of keys; sorting them was most of its
cost. Here every key is scattered into a table of about twice as many slots; each slot
keeps one writer, the "winner", and every key compares itself (exactly, on all its
integer components: the hash only picks the slot) with its slot's winner. Keys equal to
their winner are settled; the others go to the next round with a fresh slot function.
All equal keys share a slot in every round, so they settle together, on one winner. Each
round settles at least the winner of every occupied slot, and after ``_ROUNDS`` rounds
(only reached by adversarial 64-bit hash collisions) the rest is grouped by sorting.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["first_of_equal", "has_repeat"]

_ROUNDS = 8
# odd 64-bit multipliers (golden ratio and murmur/xxhash constants): the slot of hash h in
# round r is the top bits of h * _SLOT_MUL[r] (multiplicative hashing)
_SLOT_MUL = tuple(
    np.uint64(c)
    for c in (
        0x9E3779B97F4A7C15,
        0xC2B2AE3D27D4EB4F,
        0x165667B19E3779F9,
        0xFF51AFD7ED558CCD,
        0xC4CEB9FE1A85EC53,
        0x27D4EB2F165667C5,
        0x94D049BB133111EB,
        0xBF58476D1CE4E5B9,
    )
)
_ROW_MUL = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xC2B2AE3D27D4EB4F), np.uint64(0x165667B1))


def _slots(h: NDArray[np.uint64], r: int) -> tuple[NDArray[np.int64], int]:
    """Slots of hashes ``h`` in round ``r`` and the table size (a power of two >= 2 len(h))."""
    bits = max(len(h).bit_length() + 1, 4)
    s = h * _SLOT_MUL[r]
    s >>= np.uint64(64 - bits)
    return s.view(np.int64), 1 << bits  # below 2**bits: the same values


def _row_hash(cols: Sequence[NDArray[np.int64]]) -> NDArray[np.uint64]:
    h = cols[0].view(np.uint64) * _ROW_MUL[0]
    for c, mul in zip(cols[1:], _ROW_MUL[1:], strict=False):
        h ^= c.view(np.uint64) * mul
    return h


def first_of_equal(cols: Sequence[NDArray[np.int64]]) -> NDArray[np.intp]:
    """For rows ``i`` of the integer columns ``cols`` (1 to 3 arrays (N,) of int64): the
    smallest index ``j`` whose row equals row ``i`` exactly (so ``j <= i``, and ``j == i``
    marks the first occurrence of each distinct row)."""
    n = len(cols[0])
    todo = np.arange(n, dtype=np.intp)  # unsettled rows, ascending
    label = todo.copy()
    cur, h = list(cols), _row_hash(cols)
    for r in range(_ROUNDS):
        m = len(todo)
        if m == 0:
            return label
        slot, size = _slots(h, r)
        table = np.full(size, m, dtype=np.intp)
        # the winner of a slot is its smallest index; a settled row's group then holds no
        # smaller index (all of the group wrote to this slot), so the winner is its first
        np.minimum.at(table, slot, np.arange(m, dtype=np.intp))
        w = table.take(slot)
        same = cur[0].take(w) == cur[0]
        for c in cur[1:]:
            same &= c.take(w) == c
        label[todo] = todo.take(w)  # final for settled rows, overwritten later for the rest
        keep = np.flatnonzero(~same)
        todo, h = todo.take(keep), h.take(keep)
        cur = [c.take(keep) for c in cur]
    if len(todo):  # only after repeated full 64-bit hash collisions
        rows = np.stack(cur, axis=1)
        _, first, inv = np.unique(rows, axis=0, return_index=True, return_inverse=True)
        label[todo] = todo[first[inv.ravel()]]  # np.unique's first index is the smallest
    return label


def has_repeat(keys: NDArray[np.int64]) -> bool:
    """True when some value occurs twice or more in ``keys`` (N,) int64 (exact)."""
    k = np.ascontiguousarray(keys)
    h = k.view(np.uint64)
    for r in range(_ROUNDS):
        if len(k) < 2:
            return False
        slot, size = _slots(h, r)
        table = np.empty(size, dtype=np.intp)
        idx = np.arange(len(k), dtype=np.intp)
        table[slot] = idx  # any one writer wins the slot: equal keys settle on it together
        w = table.take(slot)
        lost = w != idx
        if (lost & (k.take(w) == k)).any():
            return True
        keep = np.flatnonzero(lost)
        k, h = k.take(keep), h.take(keep)
    return bool(len(k) > 1 and (np.diff(np.sort(k)) == 0).any())
