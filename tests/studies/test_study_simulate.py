"""Simulated participants: the whole pipeline runs end to end."""

from __future__ import annotations

import csv
import json
import sqlite3

import numpy as np

from ramure.app.cli import main
from ramure.studies.analysis import cooccurrence, groups_per_test
from ramure.studies.picks import lattice_picks, synthetic_grammars
from ramure.studies.simulate import SimulatedParticipant, simulate_study


def test_lattice_picks_order_pc1_slowest():
    picks = lattice_picks(seed=0, noise=0.0, extent=(3.0, 2.0, 1.0))
    pca = np.array([p.pca for p in picks])
    assert pca[:9, 0].max() < pca[9:18, 0].min() and pca[9:18, 0].max() < pca[18:, 0].min()
    assert pca[0].tolist() == [-3, -2, -1] and pca[13].tolist() == [0, 0, 0] and pca[26].tolist() == [3, 2, 1]
    assert [p.pca[2] for p in picks[:3]] == [-1, 0, 1]
    assert len(synthetic_grammars(4)) == 4


def test_noise_free_participant_follows_pca_distance():
    pca = np.array([p.pca for p in lattice_picks(seed=0, noise=0.0, extent=(10.0, 1.0, 1.0))])
    groups = SimulatedParticipant(noise=0.0, mean_groups=3, seed=1).sort(pca)
    assert sorted(map(tuple, groups)) == [tuple(range(1, 10)), tuple(range(10, 19)), tuple(range(19, 28))]


def test_more_noise_blurs_the_blocks():
    def block_share(noise):
        data = simulate_study(participants=6, grammars=2, noise=noise, seed=2)
        c = cooccurrence(data).astype(float)
        np.fill_diagonal(c, 0)
        within = sum(c[b : b + 9, b : b + 9].sum() for b in (0, 9, 18))
        return within / c.sum()

    assert block_share(0.05) > block_share(1.0) + 0.1


def test_simulated_study_is_reproducible_and_complete(tmp_path):
    a = simulate_study(tmp_path / "a.db", participants=4, grammars=2, tests_per_participant=1, seed=7)
    b = simulate_study(tmp_path / "b.db", participants=4, grammars=2, tests_per_participant=1, seed=7)
    assert a.n_tests == 4 and np.array_equal(a.membership, b.membership)
    assert np.array_equal(np.nan_to_num(a.usefulness), np.nan_to_num(b.usefulness))
    assert (a.membership.sum(axis=0) == 4).all()  # every image sorted in every test
    assert ((groups_per_test(a) >= 2) & (groups_per_test(a) <= 9)).all()
    assert not np.isnan(a.usefulness).any() and not np.isnan(a.difference).any()
    several = a.membership.sum(axis=1) > 1
    assert not np.isnan(a.representative_quality[several]).any()
    assert np.isnan(a.representative_quality[~several]).all()


def test_simulate_command_end_to_end(tmp_path, capsys):
    code = main(
        [
            "study",
            "simulate",
            "--participants",
            "6",
            "--grammars",
            "3",
            "--seed",
            "3",
            "--db",
            str(tmp_path / "sim.db"),
            "-o",
            str(tmp_path / "report"),
            "--store",
            str(tmp_path / "store.db"),
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["tests"] == 18 and out["participants"] == 6
    assert 2 <= out["groups_per_test"]["mean"] <= 9
    report = tmp_path / "report"
    html = (report / "index.html").read_text()
    for part in ("cooccurrence.png", "grouping.png", "ratings.png", "ANOVA tables", "Not an inference", "Qualifiers"):
        assert part in html
    for png in ("cooccurrence.png", "grouping.png", "ratings.png", "qualifiers.png"):
        assert (report / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(report / "cooccurrence_all.csv") as fh:
        rows = list(csv.reader(fh))
    matrix = np.array([r[1:] for r in rows[1:]], dtype=int)
    assert matrix.shape == (27, 27) and (matrix == matrix.T).all() and matrix[0, 0] == 18
    conn = sqlite3.connect(tmp_path / "store.db")
    n, quals = conn.execute("SELECT count(*), count(DISTINCT qualifier) FROM qualifier_points").fetchone()
    conn.close()
    assert n == out["qualifier_points"] > 0 and quals >= 4
    assert out["qualifiers"]["top"][0]["groups"] >= out["qualifiers"]["top"][-1]["groups"]
