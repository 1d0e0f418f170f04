"""Does the desktop fit in 600 MB?  Honda n = 17's editing session under a memory limit (issue 14).

``VmHWM`` counts every resident page, the libraries' clean file pages included, which the
kernel drops whenever memory is short.  Here the session of
:func:`bench_speed.desktop_memory` runs in a memory cgroup of its own, after the page cache
is dropped so that the libraries' pages are charged to it.  This module runs in a process
of its own (``benchmarks/run.py``) that has no Qt or VTK mapped: pages another process
maps stay charged to that process, and the limit would not count them.
"""

from __future__ import annotations

import pathlib
import time

from bench_speed import _median_ms, _plain, desktop_memory


def _memory_cgroup() -> tuple[pathlib.Path, int] | None:
    """This process's memory cgroup folder and the cgroup version (1: the ``memory`` controller's
    hierarchy, 2: the unified one with ``memory.max``), if one is mounted; None otherwise."""
    try:
        lines = pathlib.Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return None
    for line in lines:
        number, controllers, path = line.split(":", 2)
        if "memory" in controllers.split(","):
            folder = pathlib.Path("/sys/fs/cgroup/memory") / path.lstrip("/")
            if (folder / "memory.limit_in_bytes").exists():
                return folder, 1
    for line in lines:
        number, _, path = line.split(":", 2)
        for root in (pathlib.Path("/sys/fs/cgroup"), pathlib.Path("/sys/fs/cgroup/unified")):
            folder = root / path.lstrip("/")
            if number == "0" and (folder / "memory.max").exists():
                return folder, 2
    return None


#: The files of a memory cgroup: limit, charged peak, OOM kills (v1, v2).
_CGROUP_FILES = {
    1: ("memory.limit_in_bytes", "memory.max_usage_in_bytes", "memory.oom_control"),
    2: ("memory.max", "memory.peak", "memory.events"),
}


def desktop_in_memory_limit(limit_mb: int | None, n: int = 17) -> dict:
    """:func:`desktop_memory`'s session (first frame, a pick, five regrow/undo edits with redos),
    run in a memory cgroup of its own limited to ``limit_mb`` (None: no limit, the same harness
    for comparison), after the page cache is dropped so that the libraries' pages are charged to
    it: the kernel then keeps the session within the limit by dropping clean pages it does not
    use (there is no swap here), and the edits' times to the frame (``frame_ms``) say what that
    costs.  ``charged_peak_mb`` is the cgroup's peak (its own memory and the page cache it
    read), ``oom_kills`` the kernel's out-of-memory kills in it.  Needs root (the cgroup, the
    page cache); else ``{"error": ...}``.  Drops the whole machine's page cache."""
    import os

    found = _memory_cgroup()
    if found is None:
        return {"error": "no memory cgroup mounted"}
    base, version = found
    limit_file, peak_file, events_file = _CGROUP_FILES[version]
    group = base / f"ramure-bench-{os.getpid()}"
    try:
        group.mkdir()
    except OSError as exc:
        return {"error": f"cannot make a memory cgroup: {exc}"}
    try:
        if limit_mb is not None:
            (group / limit_file).write_text(str(limit_mb * 2**20))
        os.sync()
        pathlib.Path("/proc/sys/vm/drop_caches").write_text("3")
        start = time.perf_counter()
        record = desktop_memory(n, hide=("mypy",), cgroup=group)
        seconds = time.perf_counter() - start
        peak = int((group / peak_file).read_text()) / 2**20
        events = dict(line.split() for line in (group / events_file).read_text().splitlines() if len(line.split()) == 2)
    except OSError as exc:
        return {"error": f"cannot limit the session's memory: {exc}"}
    finally:
        for _ in range(50):  # the child has exited; its charges leave the group shortly after
            try:
                group.rmdir()
                break
            except OSError:
                time.sleep(0.1)
    return {
        **record,
        "limit_mb": limit_mb,
        "seconds": round(seconds, 1),
        "charged_peak_mb": round(peak, 1),
        "oom_kills": int(events.get("oom_kill", 0)),
    }


def bench_memory_limit_honda_n17():
    """Does the desktop fit in 600 MB?  :func:`desktop_in_memory_limit`'s session under a 600 MB
    limit and with none (each after the page cache is dropped): ``ok`` when the limited session
    completes with no out-of-memory kill and its later regrows and undos still meet their targets
    (100 / 50 ms, medians to the frame).  The unlimited session's ``VmHWM`` counts clean library
    pages the kernel can drop at any time; the limit shows what the session needs resident."""
    runs = {}
    for name, limit in (("limited", 600), ("unlimited", None)):
        record = desktop_in_memory_limit(limit)
        if "error" in record:
            return {"seconds": None, "error": record["error"], "ok": False}
        frames = record.get("frame_ms") or {}
        runs[name] = {
            "completed": "after_five_edits_mb" in record,
            "oom_kills": record["oom_kills"],
            "charged_peak_mb": record["charged_peak_mb"],
            "vmhwm_mb": {k: record.get(k) for k in ("peak_mb", "after_edits_mb", "after_five_edits_mb")},
            "first_regrow_ms": (frames.get("regrow") or [None])[0],
            "regrow_ms": _median_ms((frames.get("regrow") or [])[1:]),
            "undo_ms": _median_ms(frames.get("undo") or []),
            "seconds": record["seconds"],
        }
    limited = runs["limited"]
    ok = (
        limited["completed"]
        and limited["oom_kills"] == 0
        and limited["regrow_ms"] is not None
        and limited["undo_ms"] is not None
        and limited["regrow_ms"] <= 100
        and limited["undo_ms"] <= 50
    )
    return _plain({"seconds": limited["seconds"], "limit_mb": 600, **runs, "ok": bool(ok)})
