"""The live touch queue (``app.engine.sources.QueueSource``) whatever the order its
producers' items arrive in: every sample handed out once, none lost, each call's
samples sorted by stamp, none before its block, none later than the first call after it
arrived."""

import queue
import threading

import numpy as np
from hypothesis import given, settings, strategies as st

from frictex.app.engine.sources import QueueSource
from frictex.rendering.input.trace_file import MOVE

BLOCK_S = 0.005


def taken_samples(trace):
    """(t_s, producer, sample number) of each sample a take handed out, in order."""
    if trace is None:
        return []
    return list(zip(trace.t_s.tolist(), trace.finger.tolist(), trace.x_mm.astype(int).tolist()))


@st.composite
def interleavings(draw):
    """Producers (2-4), each putting items of 1-3 samples with non-decreasing stamps
    (s) on a grid of quarter blocks, so that stamps tie across producers and with block
    starts; the puts of all producers interleaved in any order, with takes (at blocks
    that never go back) anywhere between them. Returns the script: ("put", items) and
    ("take", k) steps."""
    producers = draw(st.integers(2, 4))
    queues = []
    number = 0
    for p in range(producers):
        stamps = sorted(draw(st.lists(st.integers(0, 80), min_size=1, max_size=12)))
        items, i = [], 0
        while i < len(stamps):
            size = draw(st.integers(1, 3))
            items.append([(stamps[j] * BLOCK_S / 4, p, number + j - i)
                          for j in range(i, min(i + size, len(stamps)))])
            number += len(items[-1])
            i += size
        queues.append(items)
    script, k = [], 0
    while any(queues):
        if draw(st.booleans()):
            k += draw(st.integers(0, 4))
            script.append(("take", k))
        p = draw(st.sampled_from([i for i, q in enumerate(queues) if q]))
        script.append(("put", queues[p].pop(0)))
    script.append(("take", 10_000))  # everything is due by then
    return script


def put(q, samples):
    q.put_nowait([(t, producer, float(n), 20.0, 0.5, MOVE) for t, producer, n in samples])


@settings(max_examples=300, derandomize=True, deadline=None)
@given(script=interleavings())
def test_interleaved_producers_lose_nothing_and_keep_time_order(script):
    q = queue.Queue()
    source = QueueSource(q, BLOCK_S)
    arrived, served = [], []  # in arrival order; (take's k, sample) in order handed out
    for step, arg in script:
        if step == "put":
            put(q, arg)
            arrived.extend(arg)
            continue
        before = {s for _, s in served}
        trace, n_run = source.take(arg, 1)
        got = taken_samples(trace)
        assert n_run == 1
        assert [s[0] for s in got] == sorted(s[0] for s in got)  # by time
        assert all(t <= arg * BLOCK_S for t, _, _ in got)  # none before its block
        # every sample due that had arrived, each once: none lost, none served twice
        due = [s for s in arrived if s[0] <= arg * BLOCK_S and s not in before]
        assert sorted(got) == sorted(due) and len(set(got)) == len(got)
        # equal stamps in the order they arrived
        assert got == sorted(due, key=lambda s: s[0])
        served += [(arg, s) for s in got]
    assert sorted(s for _, s in served) == sorted(arrived)


def test_two_items_out_of_order_are_each_served_once():
    """The case that went wrong: the second item stamped before the first; the first
    call took the later sample for the earlier one, served it twice and dropped the
    other (or failed: time going back)."""
    q = queue.Queue()
    source = QueueSource(q, BLOCK_S)
    put(q, [(0.004, 0, 0)])
    put(q, [(0.001, 1, 1)])
    put(q, [(0.012, 1, 2)])
    first = taken_samples(source.take(1, 1)[0])
    second = taken_samples(source.take(3, 1)[0])
    assert first == [(0.001, 1, 1), (0.004, 0, 0)]
    assert second == [(0.012, 1, 2)]


def test_producer_threads_and_a_consumer_lose_and_repeat_nothing():
    """Three threads putting stamped items as fast as they can while the consumer takes
    block after block: at the end every sample was handed out exactly once, each call's
    in time order."""
    q = queue.Queue()
    source = QueueSource(q, BLOCK_S)
    per_thread = 2_000
    go = threading.Event()

    def produce(p):
        rng = np.random.default_rng(p)
        t = 0.0
        go.wait()
        for n in range(per_thread):
            t += float(rng.exponential(BLOCK_S / 3))
            put(q, [(t, p, p * per_thread + n)])

    threads = [threading.Thread(target=produce, args=(p,)) for p in range(3)]
    for thread in threads:
        thread.start()
    go.set()
    served, k = [], 0
    while any(thread.is_alive() for thread in threads):
        got = taken_samples(source.take(k, 1)[0])
        assert [s[0] for s in got] == sorted(s[0] for s in got)
        served += got
        k += 1
    for thread in threads:
        thread.join()
    served += taken_samples(source.take(10**9, 1)[0])
    assert sorted(n for _, _, n in served) == list(range(3 * per_thread))
