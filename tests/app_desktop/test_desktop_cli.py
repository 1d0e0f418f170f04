"""``python -m ramure.app.desktop``: the headless screenshot run of ``make run`` and its errors."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from PySide6.QtGui import QImage

from ramure.app.desktop.view.thumbnails import pixel_variance
from desktop_helpers import HONDA, ROOT

pytestmark = pytest.mark.gui


def run(*args, timeout=60):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "ramure.app.desktop", *map(str, args)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_screenshot_and_quit(artifacts):
    out = artifacts / "desktop_cli_window.png"
    out.unlink(missing_ok=True)
    done = run(HONDA, "-n", "8", "--screenshot", out, "--quit-after", "1")
    assert done.returncode == 0, done.stderr
    image = QImage(str(out))
    assert image.width() >= 1000 and pixel_variance(image) > 100


def test_a_bad_grammar_is_one_line_and_exit_2(tmp_path):
    bad = tmp_path / "bad.lsys"
    bad.write_text("n: 2\nw: A(\n")
    done = run(bad, "--quit-after", "0.1")
    assert done.returncode == 2 and "line 2" in done.stderr and "Traceback" not in done.stderr
    done = run(tmp_path / "missing.lsys", "--quit-after", "0.1")
    assert done.returncode == 2 and "missing.lsys" in done.stderr
