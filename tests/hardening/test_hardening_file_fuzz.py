"""Sessions, MTG files and the desktop's settings file under fuzz (``tests/hardening/fuzz_files.py``)."""

from __future__ import annotations

import types

import pytest

from tests.hardening.fuzz_files import READERS, campaign


def test_a_fixed_slice_of_the_file_fuzzers_has_no_crash_and_changes_nothing():
    counts = campaign(90, seed=0)
    bad = {key: n for key, n in counts.items() if key[1] not in ("ok", "refused")}
    assert not bad, counts
    for reader in READERS:  # each reader accepts some inputs and refuses others (or reads them all)
        assert counts[reader, "ok"] > 0, counts
    assert counts["session", "refused"] > 0 and counts["mtg", "refused"] > 0


@pytest.mark.parametrize(
    "stored",
    [
        "@Point(1 2)",  # Qt decodes it to a QPoint: pathlib raised TypeError
        "@Size(3 4), {good}",
        "@ByteArray(abc)",
        "12, {good}",
        "x" * 5000,  # a name too long: exists() raised OSError
        "{good}, a\\0b.lsys",  # a NUL byte
        # found by the large run (files seed 103): Qt raised "Can't find converter for 'qfloat16'"
        "\\0, @Variant(\\0\\0\\0\\x2\\0\\0\\0\\x5), @Variant(\\0\\0\\0\\x7f0\\6QPoint\\0\\0\\0\\0\\x1\\0\\0\\0\\x2)",
    ],
)
def test_recent_files_skip_entries_that_are_not_paths(tmp_path, stored):
    """Issue 37: the desktop reads its settings file from disk; an entry of another type or
    one that is not a path raised in the File menu.  Such entries are skipped."""
    from PySide6.QtCore import QSettings

    from ramure.app.desktop.menus.files import FileActions

    good = tmp_path / "plant.lsys"
    good.write_text("n: 1\nw: F\n")
    path = tmp_path / "settings.conf"
    path.write_text("[General]\nrecent=" + stored.replace("{good}", str(good)) + "\n")
    recent = FileActions.recent(types.SimpleNamespace(settings=QSettings(str(path), QSettings.Format.IniFormat)))
    assert recent == ([str(good)] if "{good}" in stored else [])


def test_the_large_run_s_worker_fuzzes_under_the_address_space_limit():
    """The large run (benchmarks/bench_fuzz_large.py) in small: one chunk of each reader, each
    in a process under the 2 GB limit, prints its figures; none crashes."""
    import json
    import os
    import pathlib
    import subprocess
    import sys

    root = pathlib.Path(__file__).resolve().parents[2]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", QT_QPA_PLATFORM="offscreen")
    for reader, inputs in (("lsys", 6), ("studies", 3), ("files", 6)):
        cmd = [sys.executable, "-m", "tests.hardening.fuzz_all", "--reader", reader, "--inputs", str(inputs), "--seed", "4"]
        out = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True, timeout=600)
        record = json.loads(out.stdout.strip().splitlines()[-1])
        assert out.returncode == 0, out.stderr[-2000:]
        assert record["inputs"] == inputs and record["crashes"] == 0 and record["slow"] == 0
        assert record["limit_mb"] == 2048 and 0 < record["peak_mb"] < 2048
        assert sum(record["outcomes"].values()) == inputs
