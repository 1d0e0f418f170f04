"""``ramure study`` sub-commands, run through the real CLI entry point."""

from __future__ import annotations

import json
import sqlite3

import numpy as np
import pytest
from scipy import stats

from ramure.app.cli import main
from ramure.studies.picks import lattice_picks


def run(capsys, *argv):
    code = main(["study", *argv])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if out.strip() else None), err


def test_anova_command_rechecks_a_published_table(tmp_path, capsys):
    rng = np.random.default_rng(4)
    table = np.round(rng.uniform(1, 4, size=(27, 7)), 2)
    lines = ["image\tAB\tTB\tHM\tHS\tT1\tT2\tT3"] + [
        "\t".join([str(i + 1), *(f"{v:.2f}".replace(".", ",") for v in row)]) for i, row in enumerate(table)
    ]
    (tmp_path / "t.tsv").write_text("\n".join(lines) + "\n")
    code, out, _ = run(capsys, "anova", str(tmp_path / "t.tsv"))
    assert code == 0
    assert out["columns"] == ["AB", "TB", "HM", "HS", "T1", "T2", "T3"] and out["rows"] == 27
    ref_g, ref_i = stats.f_oneway(*table.T), stats.f_oneway(*table)
    assert out["across_grammars"]["F"] == pytest.approx(ref_g.statistic)
    assert out["across_grammars"]["p"] == pytest.approx(ref_g.pvalue)
    assert out["across_grammars"]["F_crit"] == pytest.approx(stats.f.ppf(0.95, 6, 182))
    assert out["across_image_points"]["F"] == pytest.approx(ref_i.statistic)
    assert out["across_image_points"]["F_crit"] == pytest.approx(stats.f.ppf(0.95, 26, 162))
    assert out["across_grammars"]["verdict"].startswith("not significant") == (ref_g.pvalue >= 0.05)
    assert out["column_means"][0] == pytest.approx(table[:, 0].mean())
    # Without the label column the first column would be data: forcing it changes the result.
    code, forced, _ = run(capsys, "anova", str(tmp_path / "t.tsv"), "--no-row-labels")
    assert len(forced["columns"]) == 8


def test_user_errors_exit_2_without_traceback(tmp_path, capsys):
    (tmp_path / "bad.tsv").write_text("a\tb\n1\tx\n2\t3\n")
    code, out, err = run(capsys, "anova", str(tmp_path / "bad.tsv"))
    assert code == 2 and out is None and "'x' is not a number" in err and "Traceback" not in err
    code, _, err = run(capsys, "analyze", str(tmp_path / "none.db"), "-o", str(tmp_path / "r"))
    assert code == 2 and "no such study file" in err
    code, _, err = run(capsys, "create", str(tmp_path / "s.db"), "--grammar", "honda")
    assert code == 2 and "NAME=EXPLORATION_DIR" in err


def test_create_status_analyze_export(tmp_path, capsys):
    explore = tmp_path / "explore"
    for name, seed in (("honda", 1), ("tree2", 2)):
        (explore / name).mkdir(parents=True)
        (explore / name / "picks.json").write_text(
            json.dumps([dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params) for p in lattice_picks(seed)])
        )
    db = tmp_path / "study.db"
    code, out, _ = run(
        capsys,
        "create",
        str(db),
        "--grammar",
        f"honda={explore / 'honda'}",
        "--grammar",
        f"tree2={explore / 'tree2'}",
        "--budget-minutes",
        "20",
    )
    assert code == 0 and out["grammars"] == ["honda", "tree2"] and out["budget_minutes"] == 20

    from ramure.studies.simulate import run_simulation
    from ramure.studies.storage import Study

    with Study.open(db) as study:
        run_simulation(study, participants=4, seed=1)

    code, out, _ = run(capsys, "status", str(db))
    assert out["tests"] == 8 and out["finished"] == 8 and len(out["participants"]) == 4

    code, out, _ = run(capsys, "analyze", str(db), "-o", str(tmp_path / "report"))
    assert code == 0 and out["tests"] == 8 and out["participants"] == 4
    assert (tmp_path / "report" / "index.html").is_file()
    assert set(out["anova"]["usefulness"]) == {"across_grammars", "across_image_points"}
    # The per-image table of the report re-checks with the anova command.
    code, again, _ = run(capsys, "anova", str(tmp_path / "report" / "image_ratings_usefulness.tsv"))
    assert again["across_grammars"]["F"] == pytest.approx(out["anova"]["usefulness"]["across_grammars"]["F"])

    code, out, _ = run(capsys, "export-csv", str(db), "-o", str(tmp_path / "csv"))
    assert code == 0 and len(out["files"]) == 8  # six tables, the codebook and its R note
    code, out, _ = run(capsys, "export-qualifiers", str(db), "--store", str(tmp_path / "q.db"))
    assert code == 0 and out["points"] > 0 and out["source"] == "study:study"
    conn = sqlite3.connect(tmp_path / "q.db")
    assert conn.execute("SELECT count(*) FROM qualifier_points").fetchone()[0] == out["points"]
    conn.close()


def test_create_with_a_config_then_withdraw_and_delete_by_external_id(tmp_path, capsys):
    from ramure.studies.storage import Study

    explore = tmp_path / "explore" / "honda"
    explore.mkdir(parents=True)
    rows = [dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params) for p in lattice_picks(1)]
    (explore / "picks.json").write_text(json.dumps(rows))
    (tmp_path / "bad.json").write_text(json.dumps({"likert": {"levels": ["a", "b"]}}))
    db = tmp_path / "study.db"
    code, _, err = run(capsys, "create", str(db), "--grammar", f"honda={explore}", "--config", str(tmp_path / "bad.json"))
    assert code == 2 and "likert.levels: expected the 4 level names" in err and not db.exists()
    (tmp_path / "c.json").write_text(json.dumps({"contact": "lab@example.org", "framing": "own"}))
    code, out, _ = run(capsys, "create", str(db), "--grammar", f"honda={explore}", "--config", str(tmp_path / "c.json"))
    assert code == 0 and out["framing"] == "own"
    with Study.open(db) as study:
        assert study.config().contact == "lab@example.org"
        study.add_participant("P1", consent=True, external_id="prolific-5f3a")
        study.add_participant("P2", consent=True)
    code, out, _ = run(capsys, "withdraw", str(db), "prolific-5f3a")
    assert code == 0 and out == dict(db=str(db), participant="P1", withdrawn=True, deleted=False)
    code, out, _ = run(capsys, "withdraw", str(db), "P2", "--delete")
    assert code == 0 and out["deleted"]
    code, out, _ = run(capsys, "status", str(db))
    assert [(p["code"], p["consent"], bool(p["withdrawn_at"])) for p in out["participants"]] == [("P1", False, True)]
    code, _, err = run(capsys, "withdraw", str(db), "P9")
    assert code == 2 and "no participant 'P9'" in err
