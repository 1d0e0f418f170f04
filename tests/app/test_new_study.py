"""New study from an exploration: the Qt-free function both front ends call (ramure.app.new_study)."""

from __future__ import annotations

import hashlib
import pathlib
import sqlite3

import numpy as np
import pytest

from ramure.app.new_study import add_to_study, new_study, serve_command
from ramure.studies.errors import StudyInputError

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def exploration():
    from ramure.metrics import explore

    return explore(ROOT / "grammars" / "honda_sympodial.lsys", n=3, n_jobs=1, cache=False)


def test_new_study_writes_picks_pictures_and_a_servable_study(exploration, tmp_path):
    from PIL import Image

    from ramure.studies.serve import check_servable
    from ramure.studies.storage import Study

    made = new_study(exploration, tmp_path / "my study", name="Honda", budget_minutes=12, size=(64, 64))
    assert made.db == tmp_path / "my study" / "study.db" and made.grammar == "honda_sympodial"
    assert made.command == f"ramure study serve '{made.db}'"  # quoted: the folder has a space
    assert (made.exploration / "picks.json").is_file() and (made.exploration / "pca.json").is_file()
    with Study.open(made.db, readonly=True) as study:
        assert study.name == "Honda" and study.grammars == ["honda_sympodial"] and study.budget_seconds == 12 * 60
        picks = study.picks("honda_sympodial")
        check_servable(study)  # every picture present, inside the study's folder
    assert [p.variant for p in picks] == exploration.picks.variant.tolist()
    digests = set()
    for pick in picks:
        image = np.asarray(Image.open(pick.image).convert("L"), float)
        assert image.shape == (64, 64) and image.std() > 5  # a drawn plant, not a blank tile
        digests.add(hashlib.sha256(image.tobytes()).hexdigest())
    assert len(digests) > 20  # the picks' own pictures, not one picture 27 times
    raw = sqlite3.connect(made.db).execute("SELECT image FROM picks ORDER BY pick_id").fetchall()
    assert raw[0][0] == "honda_sympodial/thumbs/pick_01.png"  # relative: the folder can be copied elsewhere


def test_a_folder_holding_a_study_is_refused_unchanged(exploration, tmp_path):
    made = new_study(exploration, tmp_path / "s", size=(32, 32))
    before = made.db.read_bytes()
    pictures = sorted((made.exploration / "thumbs").iterdir())
    stamps = [p.stat().st_mtime_ns for p in pictures]
    with pytest.raises(StudyInputError, match="already holds a study"):
        new_study(exploration, tmp_path / "s", size=(32, 32))
    assert made.db.read_bytes() == before and [p.stat().st_mtime_ns for p in pictures] == stamps


def test_degenerate_picks_are_refused_before_anything_is_written(exploration, tmp_path, monkeypatch):
    records = exploration.pick_records()
    same = [dict(r, variant=records[0]["variant"], params=records[0]["params"]) for r in records]
    monkeypatch.setattr(exploration, "pick_records", lambda images=None: same)
    with pytest.raises(StudyInputError, match="only 1 different plants"):
        new_study(exploration, tmp_path / "s", size=(32, 32))
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [(dict(grammar="../up"), "names a folder"), (dict(budget_minutes=0), "time budget"), (dict(grammar="a b"), "names a folder")],
)
def test_bad_settings_are_refused(exploration, tmp_path, kwargs, message):
    with pytest.raises(StudyInputError, match=message):
        new_study(exploration, tmp_path / "s", **kwargs)
    assert not (tmp_path / "s").exists()


def test_serve_command_names_the_port():
    assert serve_command("/x/study.db", port=8010) == "ramure study serve /x/study.db --port 8010"


def test_a_second_grammar_is_added_until_someone_takes_part(exploration, tmp_path):
    from ramure.studies.storage import Study

    with pytest.raises(StudyInputError, match="holds no study"):
        add_to_study(exploration, tmp_path / "s", grammar="second", size=(32, 32))
    made = new_study(exploration, tmp_path / "s", size=(32, 32))
    with pytest.raises(StudyInputError, match="already holds a stimulus set named 'honda_sympodial'"):
        add_to_study(exploration, tmp_path / "s", size=(32, 32))
    added = add_to_study(exploration, tmp_path / "s", grammar="second", size=(32, 32))
    assert added.db == made.db and added.exploration == tmp_path / "s" / "second"
    with Study.open(made.db) as study:
        assert study.grammars == ["honda_sympodial", "second"]
        assert study.picks("second")[0].image == str(tmp_path / "s" / "second" / "thumbs" / "pick_01.png")
        study.add_participant(consent=True)
    before = made.db.read_bytes()
    with pytest.raises(StudyInputError, match="participants have taken part already"):
        add_to_study(exploration, tmp_path / "s", grammar="third", size=(32, 32))
    assert made.db.read_bytes() == before and not (tmp_path / "s" / "third").exists()
