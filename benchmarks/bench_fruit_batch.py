"""``ramure fruit batch`` at scale (issue 40, section 5).

* ``fruit_batch``: ``RAMURE_BENCH_FRUIT`` fruit (default 1000) with 4 views each (256x256,
  masks, COCO files) on the default pool of 2 processes: fruit per second (wall), and
  ``cpu_fruit_per_second`` = fruit / (CPU of this process and its workers / 2), the rate on
  2 idle cores whatever the machine's load.
* ``fruit_batch_dask``: ``RAMURE_BENCH_DASK_FRUIT`` fruit (default 40) on a Dask
  ``LocalCluster`` of 1 worker, then of 2, each started and warmed before the clock
  (``--scheduler tcp://...`` then costs what a running cluster costs).  ``speedup`` =
  seconds with 1 worker / seconds with 2; it means something only on a quiet machine
  (``load_average`` is reported; with 2 cores busy elsewhere it tends to 1).
* ``fruit_level2_vs_level1``: CPU seconds per fruit (build, defects, 4 views, files in
  memory) at one and two volume subdivisions, and their ratio (11-15x before the seeds were
  carved in one batch), with the build alone.
"""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import tempfile
import time

FRUIT = int(os.environ.get("RAMURE_BENCH_FRUIT", "1000"))
DASK_FRUIT = int(os.environ.get("RAMURE_BENCH_DASK_FRUIT", "40"))
LEVEL_FRUIT = int(os.environ.get("RAMURE_BENCH_LEVEL_FRUIT", "6"))


def _cpu():
    return sum(
        r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN))
    )


def bench_fruit_batch():
    from ramure.app.fruit_dataset import make_dataset

    folder = tempfile.mkdtemp(prefix="ramure-batch-")
    try:
        c0, t0 = _cpu(), time.perf_counter()
        summary = make_dataset(folder, count=FRUIT, seed=0, views=4, workers=2)
        wall, cpu = time.perf_counter() - t0, _cpu() - c0
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return {
        "seconds": round(wall, 2),
        "fruit": FRUIT,
        "views": 4,
        "fruit_per_second": round(FRUIT / wall, 3),
        "cpu_per_core_seconds": round(cpu / 2, 2),
        "cpu_fruit_per_second": round(FRUIT / (cpu / 2), 3),
        "visible_defects": summary["visible_defects"],
        "located_defects": summary["located_defects"],
        "load_average": os.getloadavg()[0],
    }


def _dask_seconds(workers):
    from dask.distributed import Client, LocalCluster

    from ramure.app.fruit_dataset import _warm, make_dataset

    folder = tempfile.mkdtemp(prefix="ramure-dask-")
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", death_timeout=180.0)
    try:
        with Client(cluster) as client:
            client.run(_warm)
            t0 = time.perf_counter()
            make_dataset(folder, count=DASK_FRUIT, seed=0, views=4, workers=workers, scheduler=cluster.scheduler_address)
            return time.perf_counter() - t0
    finally:
        cluster.close()
        shutil.rmtree(folder, ignore_errors=True)


def bench_fruit_batch_dask():
    one = _dask_seconds(1)
    two = _dask_seconds(2)
    return {
        "seconds": round(one + two, 2),
        "fruit": DASK_FRUIT,
        "one_worker_seconds": round(one, 2),
        "two_workers_seconds": round(two, 2),
        "fruit_per_second_1": round(DASK_FRUIT / one, 3),
        "fruit_per_second_2": round(DASK_FRUIT / two, 3),
        "speedup": round(one / two, 2),
        "load_average": os.getloadavg()[0],
    }


def _per_fruit(levels):
    from ramure.app import fruit_dataset as F
    from ramure.gmap.organs.fruit import build_fruit

    recipes = [F.random_recipe(F.fruit_rng(0, i), levels=levels) for i in range(LEVEL_FRUIT + 1)]
    F.make_fruit(0, recipes[0], levels=levels)  # warm: imports, renderer
    whole, build = [], []
    for i, recipe in enumerate(recipes[1:], 1):
        c0 = time.process_time()
        build_fruit(recipe["preset"], seed=recipe["seed"], volume_levels=levels)
        build.append(time.process_time() - c0)
        c0 = time.process_time()
        F.make_fruit(i, recipe, levels=levels)
        whole.append(time.process_time() - c0)
    F.close_plotter()
    return statistics.median(whole), statistics.median(build)


def bench_fruit_level2_vs_level1():
    t0 = time.perf_counter()
    one, build_one = _per_fruit(1)
    two, build_two = _per_fruit(2)
    return {
        "seconds": round(time.perf_counter() - t0, 2),
        "fruit": LEVEL_FRUIT,
        "level1_cpu_seconds": round(one, 3),
        "level2_cpu_seconds": round(two, 3),
        "ratio": round(two / one, 2),
        "level1_build_cpu_seconds": round(build_one, 3),
        "level2_build_cpu_seconds": round(build_two, 3),
        "build_ratio": round(build_two / build_one, 2),
    }
