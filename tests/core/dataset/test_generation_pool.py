"""The process pool generation runs its scenes on (:class:`~bpb_core.dataset.jobs.QuietPool`)."""

from __future__ import annotations

import threading

from bpb_core.dataset.jobs import QuietPool


def test_the_pool_replaces_workers_that_exit_and_ends_once_its_last_task_is_done() -> None:
    """Its worker-handler thread no longer wakes for every result, yet it still wakes when a
    worker exits (each one here after a single task: without a replacement the tasks would
    wait for ever) and when a closed pool's last task is done (else ``join`` never returns)."""
    done: list[list[int]] = []

    def run() -> None:
        pool = QuietPool(2, maxtasksperchild=1)
        done.append(pool.map(abs, range(-8, 0), chunksize=1))
        pool.close()
        pool.join()
        done.append([])

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout=60)
    assert done == [list(range(8, 0, -1)), []]
