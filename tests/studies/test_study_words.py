"""A study's own words join the vocabulary with their measured directions (issue 35 §5)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ramure.errors import RamureError
from ramure.metrics.qualifiers import QUALIFIER_METRICS, QualifierModel
from ramure.metrics.words import read_words, read_words_file, write_words
from ramure.studies.data import load_study_data
from ramure.studies.picks import synthetic_grammars
from ramure.studies.simulate import run_simulation
from ramure.studies.storage import Study
from ramure.studies.words import new_word_groups, study_words

FEATHERY = list(range(1, 8))  # the pictures our own participants call "feathery"


def _name_groups(study, grammar, word, named, times):
    """``times`` participants put ``named`` in one group, the rest in another, and call the first ``word``."""
    rest = [p for p in range(1, 28) if p not in named]
    for _ in range(times):
        s = study.session(study.add_participant(consent=True), grammar)
        s.set_groups([named, rest])
        for label, images in ((1, named), (2, rest)):
            s.set_representative(label, images[0])
            s.rate(label, representative=3, usefulness=3, difference=3)
        s.add_qualifier(1, word)
        s.add_qualifier(2, "Petits")  # a vocabulary word: not new
        s.finish()


@pytest.fixture
def simulated(tmp_path):
    grammars = synthetic_grammars(2, seed=4)
    with Study.create(tmp_path / "s.db", grammars=grammars, name="sim", durable=False) as study:
        run_simulation(study, participants=8, seed=4)
        _name_groups(study, "synth1", "Feathery!", FEATHERY, 2)
        _name_groups(study, "synth2", "feathery", FEATHERY, 1)
        _name_groups(study, "synth1", "zigzag", [20, 21], 1)
        _name_groups(study, "synth2", "pas très dense", [20, 21], 2)  # a negated known word
        yield load_study_data(study)


def _metrics(height_of_named, crown_of_named=0.0):
    """(27, 15) metrics: height (and crown width) differ between FEATHERY and the rest only."""
    m = np.ones((27, len(QUALIFIER_METRICS)))
    named = np.isin(np.arange(1, 28), FEATHERY)
    m[named, QUALIFIER_METRICS.index("height")] += height_of_named
    m[named, QUALIFIER_METRICS.index("crown_width")] += crown_of_named
    return m


def test_new_words_are_the_texts_the_vocabulary_does_not_name(simulated):
    found = new_word_groups(simulated)
    assert set(found["feathery"]["texts"]) == {"Feathery!", "feathery"} and len(found["feathery"]["groups"]) == 3
    assert "petits" not in found and "small" not in found  # French plural of a vocabulary word
    assert not [w for w in found if "dense" in w]  # "pas très dense" negates a known word
    assert all(len(w.split("-")) <= 4 for w in found)


def test_a_word_gets_the_direction_of_the_pictures_it_named(simulated):
    words, left_out = study_words(simulated, {"synth1": _metrics(2.0), "synth2": _metrics(2.0)})
    assert words["feathery"]["direction"] == {"height": 1.0}  # only the height tells them apart
    assert words["feathery"]["groups"] == 3 and words["feathery"]["grammars"] == ["synth1", "synth2"]
    assert words["feathery"]["participants"] == 3 and words["feathery"]["picks"] == 7
    assert "+1 height" in words["feathery"]["meaning"]
    assert left_out["zigzag"].startswith("named by 1 group(s)")
    # taller on one grammar, wider (and shorter) on the other: pooled by the groups (2 vs 1)
    words, _ = study_words(simulated, {"synth1": _metrics(2.0), "synth2": _metrics(-2.0, 2.0)})
    d = words["feathery"]["direction"]
    assert d["height"] > 0 and d["crown_width"] > 0 and d["height"] == pytest.approx(d["crown_width"], rel=1e-3)
    # a word whose pictures are like the others is left out, saying so
    words, left_out = study_words(simulated, {"synth1": _metrics(0.0), "synth2": _metrics(0.0)}, min_groups=1)
    assert "feathery" not in words and "do not differ" in left_out["feathery"]
    assert "zigzag" not in words  # the flat metrics do not tell its pictures apart either


def test_the_vocabulary_file_round_trips_and_drives_a_qualifier_model(simulated, tmp_path):
    words, _ = study_words(simulated, {"synth1": _metrics(2.0), "synth2": _metrics(2.0)})
    path = tmp_path / "words.json"
    write_words(path, words)
    write_words(path, {"zigzag": {"direction": {"angle_spread": 1}}}, merge=True)  # added, feathery kept
    got = read_words(path)
    assert got["feathery"] == {"height": 1.0} and got["zigzag"] == {"angle_spread": 1.0}
    assert set(got) == set(words) | {"zigzag"} and len(got) >= 3  # the simulation's free texts too
    assert read_words_file(path)["feathery"]["texts"] == ["Feathery!", "feathery"]
    deltas = np.zeros((3, len(QUALIFIER_METRICS)))
    deltas[:, QUALIFIER_METRICS.index("height")] = [-5.0, 10.0, 1.0]
    model = QualifierModel(directions=read_words(path)).fit(deltas)
    assert model.rank("feathery")[0] == 1 and model.sources_["feathery"] == "transfer"


@pytest.mark.parametrize(
    "doc, words",
    [
        ([1, 2], "not a Ramure vocabulary file"),
        ({"format": "other", "words": {}}, "not a Ramure vocabulary file"),
        ({"words": {"x": {"direction": {"heigth": 1}}}}, "a direction is {metric"),
        ({"words": {"x": {"direction": {"height": 0}}}}, "not all zero"),
        ({"words": {"x": {"direction": {"height": True}}}}, "finite weight"),
        ({"words": {"x": 3}}, "must be an object"),
    ],
)
def test_a_bad_vocabulary_file_is_refused_in_one_line(tmp_path, doc, words):
    path = tmp_path / "words.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(RamureError, match=words.replace("{", r"\{")):
        read_words(path)
    with pytest.raises(RamureError, match="vocabulary file"):
        read_words("/dev/zero")


def test_study_words_cli_then_qualify_with_the_word(tmp_path, capsys, monkeypatch):
    """End to end: an exploration, a study on it, the words, then the word as a qualifier."""
    from ramure.app.cli import main
    from ramure.metrics import explore, write_exploration
    from ramure.studies.words import pick_metrics

    cache = tmp_path / "cache"
    exp = explore("honda_monopodial", n=4, n_jobs=1, cache_dir=cache)
    write_exploration(exp, tmp_path / "honda")
    grammars = {"honda": tmp_path / "honda", "plain": synthetic_grammars(1)["synth1"]}
    with Study.create(tmp_path / "s.db", grammars=grammars) as study:
        m = pick_metrics(study, "honda")
        height = m[:, QUALIFIER_METRICS.index("height")]
        first = exp.picks.variant[0]  # derived again, each pick measures as in the sweep
        assert np.allclose(m[0], [*exp.sweep.metrics_[first], *exp.sweep.shape_metrics_[first]])
        tallest = sorted((np.argsort(-height)[:6] + 1).tolist())
        _name_groups(study, "honda", "long trunk", tallest, 3)
    out = tmp_path / "words.json"
    assert main(["study", "words", str(tmp_path / "s.db"), "-o", str(out)]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert "plain" in rec["skipped_grammars"] and "no exploration folder" in rec["skipped_grammars"]["plain"]
    direction = rec["words"]["long-trunk"]["direction"]
    assert direction["height"] > 0 and rec["words"]["long-trunk"]["groups"] == 3
    assert read_words(out)["long-trunk"] == direction
    grammar = exp.sweep.grammar_file_
    args = [str(grammar), "-n", "4", "--jobs", "1", "--cache-dir", str(cache), "--words", str(out)]
    assert main(["qualify", *args, "--qualifier", "Long Trunk", "--json"]) == 0
    applied = json.loads(capsys.readouterr().out)
    assert applied["qualifier"] == "long-trunk" and applied["source"] == "transfer"
    if applied["improved"]:  # scored along its measured direction, like any qualifier
        assert applied["moves"]["long-trunk"] > 0
    else:  # or refused as any qualifier is, naming the word (and the rival that moved more)
        assert "long-trunk" in applied["reason"] and "moved" in applied["reason"]
    assert main(["qualify", *args, "--qualifier", "long trnk"]) == 2
    assert "did you mean long trunk" in capsys.readouterr().err
    assert main(["qualify", "--list", "--words", str(out)]) == 0
    assert "long trunk" in capsys.readouterr().out
    # the collision matrix in French too (same numbers, French names)
    assert main(["qualify", *args[:-2], "--matrix", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["french"][doc["names"].index("small")] == "petit"
    assert main(["qualify", *args[:-2], "--matrix", "--lang", "fr"]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()[2:] if line.strip()}
    assert {"petit", "haut", "gros"} <= set(rows) and "small" not in rows  # bushy: no region on Honda (issue 35)
