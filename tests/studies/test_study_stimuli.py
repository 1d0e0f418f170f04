"""Stimulus sets: a study refuses picks that show the same plant twice."""

from __future__ import annotations

import json

import pytest

from ramure.app.cli import main
from ramure.studies.errors import StudyInputError
from ramure.studies.picks import NEAR_DUPLICATE_TOLERANCE, Pick, coinciding_picks, lattice_picks
from ramure.studies.storage import Study


def three_plants() -> list[Pick]:
    """What ``explore`` gives for stochastic_plant: 27 picks made of 3 variants, 9 copies each."""
    plants = [
        (5, (-11.575, 0.272, -0.001), 28.27, 1),
        (8, (-0.147, -0.093, 0.0), 28.27, 2),
        (3, (12.342, 0.259, 0.001), 23.13, 1),
    ]
    picks = []
    for pid in range(1, 28):
        variant, pca, angle, rule = plants[(pid - 1) // 9]
        picks.append(Pick(pid, variant, pca, {"rule": rule, "constants": {"a": angle}}))
    return picks


def write_picks(folder, picks):
    folder.mkdir(parents=True)
    rows = [dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params) for p in picks]
    (folder / "picks.json").write_text(json.dumps(rows))
    return folder


def test_cli_refuses_three_plants_in_one_line(tmp_path, capsys):
    folder = write_picks(tmp_path / "explore" / "stochastic", three_plants())
    code = main(["study", "create", str(tmp_path / "s.db"), "--grammar", f"sp={folder}"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "only 3 different plants among the 27 picks" in err
    assert "coincide: 1-9 | 10-18 | 19-27" in err
    assert "--seed" in err and "--beta" in err
    assert not (tmp_path / "s.db").exists()


def test_api_names_exact_duplicates_and_near_duplicates(tmp_path):
    picks = lattice_picks(seed=3)
    diagonal = sum((max(p.pca[k] for p in picks) - min(p.pca[k] for p in picks)) ** 2 for k in range(3)) ** 0.5
    # pick 5 copies pick 4's variant; pick 20 sits just inside the tolerance of pick 26, with other parameters
    copy = Pick(5, picks[3].variant, picks[4].pca, picks[4].params)
    x, y, z = picks[25].pca
    near = Pick(20, 999, (x + 0.9 * NEAR_DUPLICATE_TOLERANCE * diagonal, y, z), {"rule": 2})
    changed = [copy if p.id == 5 else near if p.id == 20 else p for p in picks]
    assert coinciding_picks(changed) == [[4, 5], [20, 26]]
    with pytest.raises(StudyInputError, match=r"grammar 'g': only 25 different plants .* coincide: 4-5 \| 20, 26 "):
        Study.create(tmp_path / "s.db", grammars={"g": changed})
    assert not (tmp_path / "s.db").exists()
    # just outside the tolerance, the same set is accepted
    far = Pick(20, 999, (x + 1.1 * NEAR_DUPLICATE_TOLERANCE * diagonal, y, z), {"rule": 2})
    assert coinciding_picks([far if p.id == 20 else p for p in picks]) == []
    with Study.create(tmp_path / "ok.db", grammars={"g": [far if p.id == 20 else p for p in picks]}) as study:
        with pytest.raises(StudyInputError, match="only 3 different plants"):
            study.add_grammar("sp", three_plants())
        assert study.grammars == ["g"]


def test_participants_see_their_own_labels_and_answers_keep_pick_ids(study, tmp_path):
    from ramure.studies.export import export_csv

    first = study.session(study.add_participant(consent=True), "honda")
    second = study.session(study.add_participant(consent=True), "honda")
    a, b = first.labels(), second.labels()
    assert sorted(a) == list(range(1, 28)) and len(set(a.values())) == 27
    assert a != b and sum(a[i] == b[i] for i in a) < 5  # another code for (nearly) every pick
    assert not any(label.isdigit() for label in a.values())  # never a pick number
    assert first.labels() == study.session(first.participant, "honda").labels()  # the same at each resume
    first.set_groups([[27, 1, 14]])
    assert first.in_order(first.groups()[0].images) == [i for i in first.order() if i in (1, 14, 27)]
    assert first.missing()[0].startswith("pictures not in any group: ") and " 2," not in first.missing()[0]
    files = export_csv(study, tmp_path / "csv")
    text = "\n".join(f.read_text() for f in files)
    assert a[27] not in text.split(",") and b[27] not in text.split(",")
