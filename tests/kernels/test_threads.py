"""kernels/threads.py: every slot runs once, on threads of its own, and a failure is raised."""

from __future__ import annotations

import threading

import pytest

from imdrive.kernels.threads import num_threads, over_threads


def test_every_slot_runs_once():
    seen = []
    lock = threading.Lock()

    def call(slot):
        with lock:
            seen.append((slot, threading.get_ident()))

    over_threads(call, 3)
    assert sorted(s for s, _ in seen) == [0, 1, 2]
    one = []
    over_threads(lambda slot: one.append(threading.get_ident()), 1)
    assert one == [threading.get_ident()]  # one slot: on the calling thread


def test_a_failing_slot_is_raised():
    def call(slot):
        if slot == 1:
            raise ValueError("slot 1")

    with pytest.raises(ValueError, match="slot 1"):
        over_threads(call, 2)


def test_num_threads_is_numbas():
    import numba

    assert num_threads() == numba.get_num_threads() >= 1


def test_slots_are_one_per_item_up_to_the_threads():
    from imdrive.kernels.threads import slots

    assert slots(0) == 1
    assert slots(1) == 1
    assert slots(10**6) == num_threads()
