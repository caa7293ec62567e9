"""The GIL is released while vibro computes: a long simulation in a Python thread leaves the main
thread free to run Python code the whole time (were the GIL held, the main thread would stall for
the whole computation)."""
import os
import threading
import time

import vibro
from conftest import SCENES


def test_main_thread_runs_while_vibro_computes():
    scene = vibro.load_scene(os.path.join(SCENES, "fig05_coexistence.toml"),
                             set={"run.periods": 20000, "run.samples_per_period": 0})
    result = {}
    worker = threading.Thread(target=lambda: result.update(run=vibro.simulate(scene)))
    iterations, longest_gap = 0, 0.0
    start = last = time.perf_counter()
    worker.start()
    while worker.is_alive():
        sum(range(200))  # pure Python: needs the GIL
        now = time.perf_counter()
        longest_gap = max(longest_gap, now - last)
        last = now
        iterations += 1
    elapsed = time.perf_counter() - start
    worker.join()
    assert result["run"].summary["status"] == "ok"
    assert elapsed > 0.5, f"the run took {elapsed:.2f} s: too short to tell"
    # Python's switch interval is 5 ms: a held GIL would show as one gap as long as the run.
    assert longest_gap < 0.5 * elapsed, (longest_gap, elapsed)
    assert iterations > 1000, iterations
