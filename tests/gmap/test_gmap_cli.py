"""``ramure fruit``: JSON facts, VTU and PNG output, user errors."""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import pyvista as pv

from ramure.app.cli import main

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run_json(capsys, *argv):
    assert main(["fruit", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_reports_the_thesis_counts(capsys):
    record = run_json(capsys, "--preset", "round_tomato")
    assert (record["darts"], record["vertices"], record["faces_per_volume"], record["volumes"]) == (6000, 220, 720, 110)
    assert record["edges"] == 530 and record["faces"] == 421
    assert record["valid"] is True and record["seconds"] > 0
    assert record["tissues"]["pericarp"] == 100 and record["tissues"]["columella"] == 10


def test_set_and_subdivide_change_the_model(capsys):
    record = run_json(capsys, "--set", "precision=6", "--set", "ph=8", "--subdivide", "surface:1")
    assert record["darts"] == 4 * (6 * 12 * 8 + 6 * 8 * 48)
    record = run_json(capsys, "--set", "precision=6", "--set", "ph=8", "--subdivide", "volume:2", "--set", "seeds=3")
    assert record["tissues"]["seed"] == 3 and record["tissues"]["locule"] > 0
    assert record["valid"] is True


def test_region_at_a_finer_precision(capsys):
    plain = run_json(capsys, "--preset", "round_tomato")
    finer = run_json(capsys, "--preset", "round_tomato", "--region", "(5, C*, *) precision=20")
    # ring 5 of the coarse tomato: 10 cells round the trunk, each 8 hexahedra and a pillow on
    # each face it shares with the rest (its O face, C1, C3 and, for the trunk prism, its caps)
    assert finer["valid"] is True and plain["valid"] is True
    assert finer["volumes"] > plain["volumes"] - 11 + 8 * 10
    assert finer["vertices"] - finer["edges"] + finer["faces"] - finer["volumes"] == 1


def test_vtu_output_holds_the_cut_fruit(capsys, tmp_path):
    out = tmp_path / "tomato.vtu"
    record = run_json(capsys, "--cut", "z=0", "-o", str(out))
    assert record["output"] == str(out)
    grid = pv.read(out)
    assert 0 < grid.n_cells < 110 and grid.bounds[5] <= 1e-9
    assert set(np.unique(grid.cell_data["tissue"]).tolist()) == {0, 1}


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--set", "colour=red"], "unknown fruit parameter"),
        (["--set", "precision=-3"], "precision must be"),
        (["--set", "precision"], "--set expects NAME=VALUE"),
        (["--subdivide", "cubes:2"], "--subdivide expects"),
        (["--subdivide", "volume:x"], "not a whole number"),
        (["--cut", "w=1", "-o", "x.vtu"], "cut plane"),
        (["-o", "tomato.obj"], ".png picture or a .vtu grid"),
        (["--region", "(5, C*, *)"], "a label pattern and the region's parameters"),
        (["--region", "(5, C*, *) precision=30"], "times 2, 4 or 8"),
        (["--region", "(5, C*, *) precision=5"], "cannot be coarser"),
        (["--region", "(5, C*, *) ph=12"], "cannot change ph"),
    ],
)
def test_user_errors_print_one_line_and_exit_2(capsys, argv, message):
    assert main(["fruit", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_png_render_of_a_cut_tomato(tmp_path):
    out = tmp_path / "tomato.png"
    cmd = [
        sys.executable,
        "-m",
        "ramure.app.cli",
        "fruit",
        "--subdivide",
        "volume:1",
        "--cut",
        "z=0",
        "--size",
        "320x240",
        "-o",
        str(out),
    ]
    if not os.environ.get("DISPLAY"):
        if shutil.which("xvfb-run") is None:
            pytest.skip("no display and no xvfb-run")
        cmd = ["xvfb-run", "-a", *cmd]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert img.shape[:2] == (240, 320)
    rgb = img[..., :3].reshape(-1, 3)
    red = (rgb[:, 0] > 0.5) & (rgb[:, 1] < 0.35) & (rgb[:, 2] < 0.35)
    assert red.mean() > 0.05  # flesh and skin are on screen
