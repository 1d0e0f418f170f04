"""``ramure explore | metrics | qualify`` end to end, thumbnails and contact sheet included."""

import json

import numpy as np
import pytest

from ramure.app.cli import main
from ramure.lsys.regeneration.regen import Session
from ramure.metrics import plant_metrics

HONDA = "grammars/honda_sympodial.lsys"


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_explore_json_and_cache(tmp_path, capsys):
    argv = [
        "explore",
        HONDA,
        "-n",
        "3",
        "--no-thumbnails",
        "--cache-dir",
        str(tmp_path / "c"),
        "--jobs",
        "2",
        "-o",
        str(tmp_path / "out"),
        "--json",
    ]
    first = _json(capsys, argv)
    assert first["variants"] == 486 and len(first["picks"]) == 27 and not first["from_cache"]
    assert [p["id"] for p in first["picks"]] == list(range(1, 28))
    assert set(first["picks"][0]["params"]) == {"rule", "constants"}
    m = first["matching"]
    assert m["optimal"] <= m["greedy"] + 1e-9 and m["optimal"] <= m["sequential"] + 1e-9
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"variants.csv", "pca.json", "picks.json"}
    again = _json(capsys, argv)
    assert again["from_cache"] and again["picks"] == first["picks"]
    picks = json.loads((tmp_path / "out" / "picks.json").read_text())
    assert "image" not in picks[0]


def test_explore_with_thumbnails_and_contact_sheet(tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "out"
    summary = _json(
        capsys,
        [
            "explore",
            HONDA,
            "-n",
            "4",
            "--constants",
            "r1,a2",
            "--thumb-size",
            "48x40",
            "--no-cache",
            "--jobs",
            "1",
            "-o",
            str(out),
            "--json",
        ],
    )
    assert summary["variants"] == 18
    picks = json.loads((out / "picks.json").read_text())
    assert [p["image"] for p in picks] == [f"thumbs/pick_{i:02d}.png" for i in range(1, 28)]
    for p in picks[::13]:
        img = np.asarray(Image.open(out / p["image"]).convert("L"))
        assert img.shape == (40, 48) and (img < 200).sum() > 10  # a plant was drawn
    sheet = Image.open(out / "contact_sheet.png")
    assert sheet.size[0] == 9 * (48 + 6) + 6 and sheet.size[1] > 3 * 40


def test_metrics_command(capsys):
    whole = _json(capsys, ["metrics", HONDA, "-n", "5", "--json", "--tight"])
    assert whole["segments"] == 31 and whole["metrics"]["branch_count"] == 31
    assert len(whole["obb"]["corners"]) == 8
    assert 0 <= whole["tight_obb"]["reduction_percent"] < 100
    assert whole["tight_obb"]["volume"] <= whole["obb"]["volume"]
    part = _json(capsys, ["metrics", HONDA, "-n", "5", "--segments", "0-4", "--json"])
    assert part["selected_segments"] == 5 and part["metrics"]["total_length"] < whole["metrics"]["total_length"]


def test_qualify_saves_a_session_that_replays(tmp_path, capsys):
    cache = str(tmp_path / "c")
    session_path = tmp_path / "s.json"
    rec = _json(
        capsys, ["qualify", HONDA, "-n", "5", "--qualifier", "dense", "--cache-dir", cache, "-o", str(session_path), "--json"]
    )
    assert rec["improved"] and rec["after"]["branch_density"] > rec["before"]["branch_density"]
    replay = Session.load(session_path)
    assert plant_metrics(replay.derivation.skeleton()).branch_density == pytest.approx(rec["after"]["branch_density"])
    leaves = Session(HONDA, n=5).leaves_with_symbol("F")[-8:].tolist()
    sel = _json(
        capsys,
        [
            "qualify",
            HONDA,
            "-n",
            "5",
            "--qualifier",
            "Épars",
            "--cache-dir",
            cache,
            "--select",
            ",".join(map(str, leaves)),
            "--json",
        ],
    )
    # no constant of Honda changes its number of segments, and a selection keeps n: refused, plant unchanged
    assert sel["qualifier"] == "sparse" and sel["selection"] == leaves and not sel["improved"]
    assert "no constant or rule changes the number of branch segments" in sel["reason"] and sel["after"] == sel["before"]
    sel = _json(
        capsys,
        [
            "qualify",
            HONDA,
            "-n",
            "5",
            "--qualifier",
            "Haut",
            "--cache-dir",
            cache,
            "--select",
            ",".join(map(str, leaves)),
            "--climb",
            "2",  # the tips alone cannot grow taller; climbing above the cut is asked for
            "--json",
        ],
    )
    assert sel["qualifier"] == "tall" and sel["improved"] and sel["definition"]["holds"]
    assert sel["after"]["height"] > sel["before"]["height"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["explore", HONDA, "--beta", "0", "-o", "x"], "beta"),
        (["explore", HONDA, "--constants", "zz", "-o", "x"], "unknown constant"),
        (["qualify", HONDA, "--qualifier", "fluffy"], "unknown qualifier"),
        (["qualify", "grammars/algae.lsys", "--qualifier", "dense"], "no non-zero #define"),
        (["metrics", HONDA, "--select", "999999"], "not leaf id"),
        (["metrics", HONDA, "--segments", "1,x"], "--segments: 'x' is not a leaf id"),
    ],
)
def test_user_errors_exit_2_without_traceback(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path))
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_thumbnail_doctests():
    import doctest

    import ramure.app.thumbnails as thumbnails

    assert doctest.testmod(thumbnails).failed == 0
