"""jsPsych export and import: the experiment folder, and its results back into the study through the session API."""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

from jspsych_helpers import jspsych_csv, play_run, read_config
from web_helpers import make_study, snapshot

from ramure.studies.errors import StudyInputError
from ramure.studies.jspsych import JSPSYCH_CDN, export_jspsych, import_jspsych, picture_codes
from ramure.studies.serve import study_secret
from ramure.studies.storage import Study


@pytest.fixture
def exported(tmp_path):
    db = make_study(tmp_path / "study", grammars=2)
    folder = tmp_path / "experiment"
    summary = export_jspsych(db, folder)
    return db, folder, summary


def test_export_writes_a_self_contained_experiment_without_pick_numbers(exported):
    db, folder, summary = exported
    assert summary["pictures"] == 54 and summary["jspsych"].startswith(JSPSYCH_CDN)
    config = read_config(folder)
    secret = study_secret(db)
    with Study.open(db, readonly=True) as study:
        assert [s["grammar"] for s in config["sets"]] == study.grammars == ["g0", "g1"]
        for stimulus in config["sets"]:
            codes = picture_codes(secret, stimulus["grammar"])
            assert stimulus["pictures"] == [codes[pid] for pid in range(1, 28)]
            for pick in study.picks(stimulus["grammar"]):  # each picture copied under its code, byte for byte
                assert (folder / "img" / f"{codes[pick.id]}.png").read_bytes() == pathlib.Path(pick.image).read_bytes()
    names = {p.name for p in (folder / "img").iterdir()}  # the codes only: no pick_07.png
    assert names == {f"{c}.png" for g in ("g0", "g1") for c in picture_codes(secret, g).values()} and len(names) == 54
    assert "pick" not in (folder / "ramure-config.js").read_text()
    page = (folder / "index.html").read_text()
    assert f'src="{JSPSYCH_CDN}/dist/index.browser.min.js"' in page and '<script src="ramure-task.js">' in page
    assert config["levels"] == ["poor", "fair", "good", "excellent"] and "3 parts" not in config["consent"]
    assert config["completion_code"] in (folder / "README.txt").read_text()


def test_export_with_a_local_jspsych_copies_it_in(tmp_path):
    db = make_study(tmp_path / "study", grammars=1)
    fake = tmp_path / "node_modules" / "jspsych"
    (fake / "dist").mkdir(parents=True)
    (fake / "css").mkdir()
    (fake / "dist" / "index.browser.min.js").write_text("var jsPsychModule = {};")
    (fake / "css" / "jspsych.css").write_text("body {}")
    export_jspsych(db, tmp_path / "x", jspsych=fake)
    assert (tmp_path / "x" / "jspsych" / "jspsych.js").read_text() == "var jsPsychModule = {};"
    assert '<script src="jspsych/jspsych.js">' in (tmp_path / "x" / "index.html").read_text()
    with pytest.raises(StudyInputError, match="not a jsPsych package folder"):
        export_jspsych(db, tmp_path / "y", jspsych=tmp_path)
    assert not (tmp_path / "y").exists()


def test_export_refuses_a_study_without_pictures_and_a_foreign_folder(tmp_path):
    db = make_study(tmp_path / "bare", grammars=1, pictures=False)
    with pytest.raises(StudyInputError, match="pictures missing"):
        export_jspsych(db, tmp_path / "x")
    assert not (tmp_path / "x").exists()
    db = make_study(tmp_path / "study", grammars=1)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(StudyInputError, match="not empty"):
        export_jspsych(db, tmp_path / "mine")
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["notes.txt"]


def _check_stored(db, runs, codes):
    """Every answer of the played ``runs`` is in the study, in pick ids, with the page's times."""
    with Study.open(db, readonly=True) as study:
        participants = study.participants()
        assert len(participants) == len(runs) and all(p["finished"] == 2 and p["consent"] for p in participants)
        for person, trials in zip(participants, runs):
            events = study.events(person["code"])
            run = [e for e in events if e["action"] == "jspsych_run"]
            assert len(run) == 1 and run[0]["detail"]["run"] == trials[0]["ramure_run"]
            external = trials[0]["external_id"]
            assert [e["detail"]["external_id"] for e in events if e["action"] == "external_id"] == (
                [external] if external else []
            )
            for trial in trials[1:]:
                grammar = trial["grammar"]
                ids = {code: pid for pid, code in codes[grammar].items()}
                test = next(t for t in study.tests() if t["participant"] == person["code"] and t["grammar"] == grammar)
                assert test["finished_at"] is not None
                assert test["elapsed_seconds"] == pytest.approx(trial["rt"] / 1000)
                rows = study.conn.execute(
                    "SELECT g.label, g.representative, g.usefulness, g.difference, g.representative_quality, "
                    "(SELECT group_concat(pick_id) FROM "
                    "(SELECT pick_id FROM group_images WHERE group_id = g.id ORDER BY pick_id)), "
                    "(SELECT group_concat(text, '|') FROM (SELECT text FROM qualifiers WHERE group_id = g.id ORDER BY id)) "
                    "FROM groups g WHERE g.test_id = ? ORDER BY g.label",
                    (test["test"],),
                ).fetchall()
                expected = [
                    (
                        k,
                        ids[g["representative"]],
                        g["usefulness"],
                        g["difference"],
                        g["representative_quality"],
                        ",".join(str(i) for i in sorted(ids[c] for c in g["pictures"])),
                        "|".join(g["words"]),
                    )
                    for k, g in enumerate(trial["groups"], start=1)
                ]
                assert rows == expected


@pytest.mark.parametrize("form", ["json", "jatos", "csv"])
def test_results_round_trip_through_the_session_api(exported, tmp_path, form):
    db, folder, _ = exported
    config = read_config(folder)
    runs = [play_run(config, seed=1, external_id="5f3c0a1b2c3d4e5f6a7b8c9d"), play_run(config, seed=2, groups_of=5)]
    path = tmp_path / f"results.{'csv' if form == 'csv' else 'json'}"
    if form == "json":
        path.write_text(json.dumps(runs[0] + runs[1]))
    elif form == "jatos":  # JATOS's export: one result (one run's JSON array) per line
        path.write_text("\n".join(json.dumps(r) for r in runs) + "\n")
    else:
        path.write_text(jspsych_csv(runs[0] + runs[1]), newline="")
    summary = import_jspsych(db, path)
    assert summary["runs"] == 2 and summary["tests"] == 4 and summary["participants"] == ["P101", "P102"]
    secret = study_secret(db)
    _check_stored(db, runs, {g: picture_codes(secret, g) for g in ("g0", "g1")})
    from ramure.studies.data import load_study_data

    data = load_study_data(db)  # the analysis reads the imported answers, with the page's time on task
    assert data.n_tests == 4 and sorted(data.test_seconds) == pytest.approx(sorted(t["rt"] / 1000 for r in runs for t in r[1:]))


def _bad(trials, change):
    trials = json.loads(json.dumps(trials))
    change(trials)
    return trials


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda t: t[1]["groups"][0].update(usefulness=7), "usefulness is 7, not a level 1 to 4"),
        (lambda t: t[1]["groups"][0]["pictures"].append("0123456789ab"), "is not one of this stimulus set"),
        (lambda t: t[1]["groups"].pop(), r"each of the 27 pictures once \(they hold 2\d"),
        (lambda t: t[2].update(grammar="other"), "stimulus set 'other' is not in this study"),
        (lambda t: [x.update(ramure_study="0" * 16) for x in t], "from another study's export"),
        (lambda t: t.pop(0), "no consent trial"),
        (lambda t: t[1]["groups"][0].update(words=[]), "words must be a non-empty list"),
        (lambda t: t[1]["groups"][0].update(representative="0123456789ab"), "is not a picture of the group"),
        (lambda t: t[1].update(sorted_ms=10**12), "sorted_ms is .* not a time"),
        (lambda t: t.append(dict(t[1])), "answers stimulus set .* twice"),
    ],
)
def test_a_bad_results_file_is_refused_and_nothing_is_written(exported, tmp_path, change, message):
    db, folder, _ = exported
    config = read_config(folder)
    good = play_run(config, seed=3)
    bad = _bad(play_run(config, seed=4), change)
    path = tmp_path / "results.json"
    path.write_text(json.dumps(good + bad))  # a good run first: it is not stored either
    before = snapshot(db)
    with pytest.raises(StudyInputError, match=message):
        import_jspsych(db, path)
    assert snapshot(db) == before


def test_the_same_results_are_not_imported_twice(exported, tmp_path):
    db, folder, _ = exported
    path = tmp_path / "results.json"
    path.write_text(json.dumps(play_run(read_config(folder), seed=5)))
    import_jspsych(db, path)
    before = snapshot(db)
    with pytest.raises(StudyInputError, match="already imported"):
        import_jspsych(db, path)
    assert snapshot(db) == before


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty results file"),
        (b"\xff\xfe junk", "not UTF-8"),
        (b"[1, 2", "not JSON"),
        (b'"a","b"\r\n', "no 'ramure' column"),
    ],
)
def test_files_that_are_not_results_are_refused(exported, tmp_path, content, message):
    db, _, _ = exported
    path = tmp_path / "results.json"
    path.write_bytes(content)
    before = snapshot(db)
    with pytest.raises(StudyInputError, match=message):
        import_jspsych(db, path)
    assert snapshot(db) == before


def test_results_of_a_study_never_exported_are_refused(tmp_path):
    db = make_study(tmp_path / "s", grammars=1)
    path = tmp_path / "r.json"
    path.write_text("[]")
    with pytest.raises(StudyInputError, match="no jsPsych export was made"):
        import_jspsych(db, path)
    assert not (tmp_path / "s" / "study.db.web-secret").exists()


def test_cli_export_then_import(tmp_path):
    db = make_study(tmp_path / "s", grammars=2)
    ramure = [str(pathlib.Path(sys.executable).with_name("ramure"))]
    out = subprocess.run([*ramure, "study", "export-jspsych", str(db), "-o", str(tmp_path / "x")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["pictures"] == 54
    path = tmp_path / "r.json"
    path.write_text(json.dumps(play_run(read_config(tmp_path / "x"), seed=9)))
    out = subprocess.run([*ramure, "study", "import-jspsych", str(db), str(path)], capture_output=True, text=True)
    assert out.returncode == 0 and json.loads(out.stdout)["participants"] == ["P101"], out.stderr
    out = subprocess.run([*ramure, "study", "import-jspsych", str(db), str(path)], capture_output=True, text=True)
    assert out.returncode == 2 and "already imported" in out.stderr and len(out.stderr.strip().splitlines()) == 1
