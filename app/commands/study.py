"""``ramure study``: user studies on variant relevance (create, simulate, analyse, export).

Sub-commands print one JSON object on stdout::

    ramure study create study.db --grammar honda=explore/honda --grammar tree2=explore/tree2
    ramure study simulate --participants 20 --grammars 3 -o report/
    ramure study analyze study.db -o report/
    ramure study anova table.tsv
    ramure study export-csv study.db -o csv/
    ramure study export-qualifiers study.db --store qualifiers.db
    ramure study words study.db -o words.json
    ramure study status study.db
    ramure study serve study.db --port 8000
    ramure study withdraw study.db P104 --delete
    ramure study export-jspsych study.db -o experiment/
    ramure study import-jspsych study.db results.json

Wherever a command takes ``study.db`` it also takes a PostgreSQL URL,
``postgresql://user:password@host:5432/dbname`` (the ``postgres`` extra), or ``sqlite:///study.db``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

from ramure.app.cli import UserError
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.cli import Subparsers


_URL = "a PostgreSQL URL (postgresql://user@host/dbname)"
_DB_HELP = f"the study: a SQLite file, or {_URL}"


def _folder_for_postgres(args: argparse.Namespace) -> None:
    """Refuse ``--folder`` with a SQLite file: its folder is the file's own."""
    from ramure.studies.pgsql import is_database_url

    if args.folder is not None and not is_database_url(args.db):
        raise UserError(f"--folder is for a study on PostgreSQL; a SQLite study's folder is the one holding {args.db}")


def _print(obj) -> int:
    json.dump(obj, sys.stdout, indent=1, allow_nan=False, default=str)
    sys.stdout.write("\n")
    return 0


def _grammar_specs(items):
    from ramure.studies.errors import StudyInputError

    specs = {}
    for item in items or []:
        name, sep, path = item.partition("=")
        if not sep or not name or not path:
            raise StudyInputError(f"--grammar {item!r}: expected NAME=EXPLORATION_DIR")
        specs[name] = path
    return specs


def _summary(result) -> dict:
    """The short part of a report result: counts, grouping, inference, agreement, flags, top qualifiers.

    ``anova`` is the thesis's table reproduction (labelled by ``anova_label``); the verdicts are
    in ``inference``, with participants as the unit."""
    overall = result["grouping"]["all"]
    kept = result["qualifiers"]["kept"]
    return dict(
        study=result["study"],
        grammars=result["grammars"],
        participants=result["participants"],
        tests=result["tests"],
        groups=result["groups"],
        groups_per_test=overall["groups_per_test"],
        images_per_group=overall["images_per_group"],
        inference={
            m: dict(verdict=r["verdict"], significant=r["significant"], n=r["n"], warnings=r["warnings"])
            for m, r in result["inference"].items()
            if isinstance(r, dict)
        },
        agreement={g: dict(mean_ari=a["mean"], ci=a["ci"]) for g, a in result["agreement"]["groupings"].items()},
        flags=result["quality"]["flag_counts"],
        anova=result["anova"],
        anova_label=result["anova_label"],
        qualifiers=dict(
            observations=result["qualifiers"]["all"]["observations"],
            unique_texts=result["qualifiers"]["all"]["unique_texts"],
            kept_groups=kept["groups"],
            top=[dict(name=q["name"], groups=q["groups"]) for q in kept["qualifiers"][:10]],
        ),
    )


def run_create(args: argparse.Namespace) -> int:
    """``ramure study create``: a new study database with its grammars, name and time budget; prints them as
    JSON; returns 0.
    """
    from ramure.studies.design import read_config
    from ramure.studies.storage import Study

    if not 32 <= args.picture_size <= 2048:
        raise UserError(f"--picture-size must be 32 to 2048 pixels, not {args.picture_size}")
    _folder_for_postgres(args)
    config = read_config(args.config) if args.config else None  # checked before any file is made
    with Study.create(
        args.db,
        grammars=_grammar_specs(args.grammar),
        name=args.name,
        budget_minutes=args.budget_minutes,
        config=config,
        folder=args.folder,
    ) as study:
        pictures = {}
        if not args.no_render:
            from ramure.app.stimuli import render_stimuli

            pictures = render_stimuli(study, size=args.picture_size)
        return _print(
            dict(
                db=study.where,
                name=study.name,
                grammars=study.grammars,
                budget_minutes=study.budget_seconds / 60,
                framing=study.config().framing,
                pictures=pictures,
            )
        )


def run_withdraw(args: argparse.Namespace) -> int:
    """``ramure study withdraw``: leave a participant (code or external id) out of analyses, or erase
    every answer with ``--delete``; prints what was done as JSON; returns 0."""
    from ramure.studies.storage import Study

    with Study.open(args.db) as study:
        code = study.find_participant(args.participant)
        study.withdraw(code, delete=args.delete)
        return _print(dict(db=study.where, participant=code, withdrawn=True, deleted=bool(args.delete)))


def run_simulate(args: argparse.Namespace) -> int:
    """``ramure study simulate``: run a study with simulated participants, analyse it and write the report (and
    the qualifier points with ``--store``); returns 0.
    """
    import tempfile

    from ramure.studies.data import load_study_data
    from ramure.studies.picks import synthetic_grammars
    from ramure.studies.qualifiers import SynonymTable, export_qualifier_points, labelled_points
    from ramure.studies.report import analyze, write_report
    from ramure.studies.simulate import run_simulation
    from ramure.studies.storage import Study

    for option, value in (
        ("--participants", args.participants),
        ("--grammars", args.grammars),
        ("--tests-per-participant", args.tests_per_participant),
    ):
        if value is not None and value < 1:
            raise UserError(f"{option} must be at least 1, not {value}")
    if not 0 <= args.noise < float("inf"):
        raise UserError(f"--noise must be a number >= 0, not {args.noise}")
    grammars = _grammar_specs(args.grammar) or synthetic_grammars(args.grammars, seed=args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        db = pathlib.Path(args.db) if args.db else pathlib.Path(tmp) / "simulated.db"
        with Study.create(db, grammars=grammars, name=args.name, durable=False) as study:
            run_simulation(study, args.participants, args.tests_per_participant, args.noise, args.seed)
            data = load_study_data(study)
        synonyms = args.synonyms or []
        if args.output:
            result = write_report(data, args.output, synonyms=synonyms)
        else:
            result = analyze(data, synonyms=synonyms)
        out = dict(
            db=str(db) if args.db else None,
            report=str(pathlib.Path(args.output) / "index.html") if args.output else None,
            **_summary(result),
        )
        if args.store:
            rows = labelled_points(data, SynonymTable.load(*synonyms))
            out["qualifier_points"] = export_qualifier_points(rows, args.store)
            out["store"] = str(args.store)
    return _print(out)


def run_analyze(args: argparse.Namespace) -> int:
    """``ramure study analyze``: write the HTML report of a study database to ``-o`` and print its summary;
    returns 0.
    """
    from ramure.studies.data import load_study_data
    from ramure.studies.report import write_report

    data = load_study_data(args.db, finished_only=not args.include_unfinished)
    result = write_report(
        data,
        args.output,
        alpha=args.alpha,
        synonyms=args.synonyms or [],
        min_usefulness=args.min_usefulness,
        figures=not args.no_figures,
    )
    return _print(dict(report=str(pathlib.Path(args.output) / "index.html"), files=len(result["files"]), **_summary(result)))


def run_anova(args: argparse.Namespace) -> int:
    """``ramure study anova``: the one-way ANOVA of a CSV table of scores (columns are the groups), printed as
    JSON; returns 0.
    """
    import numpy as np

    from ramure.studies.anova import anova_table, read_table

    values, rows, columns = read_table(args.table, row_labels=args.row_labels)
    result = anova_table(values, alpha=args.alpha)
    means = [float(c[~np.isnan(c)].mean()) if (~np.isnan(c)).any() else None for c in values.T]
    return _print(dict(table=str(args.table), rows=len(rows), columns=columns, column_means=means, alpha=args.alpha, **result))


def run_export_csv(args: argparse.Namespace) -> int:
    """``ramure study export-csv``: write the study's tables as CSV files to ``-o``; returns 0."""
    from ramure.studies.export import export_csv

    files = export_csv(args.db, args.output, synonyms=args.synonyms or [])
    return _print(dict(files=[str(f) for f in files]))


def run_export_qualifiers(args: argparse.Namespace) -> int:
    """``ramure study export-qualifiers``: turn the study's labelled picks into qualifier points in the store
    ``--store`` and print how many per qualifier; returns 0.
    """
    from ramure.studies.data import load_study_data
    from ramure.studies.qualifiers import SynonymTable, export_qualifier_points, labelled_points

    data = load_study_data(args.db)
    rows = labelled_points(
        data, SynonymTable.load(*(args.synonyms or [])), min_usefulness=args.min_usefulness, source=args.source
    )
    count = export_qualifier_points(rows, args.store)
    per: dict[str, int] = {}
    for r in rows:
        per[r["qualifier"]] = per.get(r["qualifier"], 0) + 1
    return _print(
        dict(
            store=str(args.store),
            source=rows[0]["source"] if rows else args.source,
            points=count,
            per_qualifier=dict(sorted(per.items())),
        )
    )


def run_words(args: argparse.Namespace) -> int:
    """The study's new words with their measured directions, added to the vocabulary file ``-o``."""
    from ramure.errors import RamureError
    from ramure.metrics.words import write_words
    from ramure.studies.data import load_study_data
    from ramure.studies.qualifiers import SynonymTable
    from ramure.studies.storage import Study
    from ramure.studies.words import pick_metrics, study_words

    if args.min_groups < 1:
        raise UserError(f"--min-groups must be at least 1, not {args.min_groups}")
    metrics, skipped = {}, {}
    with Study.open(args.db, readonly=True) as study:
        for grammar in study.grammars:
            try:
                metrics[grammar] = pick_metrics(study, grammar, args.grammars_dir)
            except RamureError as exc:
                skipped[grammar] = str(exc)
        data = load_study_data(study)
    if not metrics:
        raise UserError(f"{args.db}: no grammar's picks can be measured ({'; '.join(skipped.values())})")
    words, left_out = study_words(data, metrics, SynonymTable.load(*(args.synonyms or [])), args.min_groups)
    write_words(args.output, words, merge=True)
    return _print(
        dict(
            output=str(args.output),
            words={w: dict(direction=e["direction"], groups=e["groups"]) for w, e in words.items()},
            left_out=left_out,
            skipped_grammars=skipped,
        )
    )


def run_status(args: argparse.Namespace) -> int:
    """``ramure study status``: print a study's grammars, budget, participants and finished tests as JSON (the
    database is opened read-only); returns 0.
    """
    from ramure.studies.storage import Study

    with Study.open(args.db, readonly=True) as study:
        tests = study.tests()
        return _print(
            dict(
                db=study.where,
                name=study.name,
                grammars=study.grammars,
                budget_minutes=study.budget_seconds / 60,
                participants=study.participants(),
                tests=len(tests),
                finished=sum(t["finished_at"] is not None for t in tests),
            )
        )


def run_serve(args: argparse.Namespace) -> int:
    """``ramure study serve``: serve the web study from the database on ``--host``:``--port`` until stopped,
    printing its addresses first; returns 0.
    """
    from ramure.studies.serve import serve

    if not 0 < args.port < 65536:
        raise UserError(f"--port must be from 1 to 65535, not {args.port}")
    _folder_for_postgres(args)

    def announce(addresses: dict) -> None:
        _print(addresses)
        sys.stdout.flush()

    serve(args.db, host=args.host, port=args.port, announce=announce, folder=args.folder)
    return 0


def run_export_jspsych(args: argparse.Namespace) -> int:
    """``ramure study export-jspsych``: write the study's pictures and task as a jsPsych experiment
    folder (for JATOS or Pavlovia); prints what was written as JSON; returns 0."""
    from ramure.studies.jspsych import export_jspsych

    return _print(export_jspsych(args.db, args.output, jspsych=args.jspsych))


def run_import_jspsych(args: argparse.Namespace) -> int:
    """``ramure study import-jspsych``: store a jsPsych results file's runs as new participants (all or
    nothing); prints what was imported as JSON; returns 0."""
    from ramure.studies.jspsych import import_jspsych

    return _print(import_jspsych(args.db, args.results))


def register(subparsers: Subparsers) -> None:
    """Add ``study`` and its subcommands (create, simulate, analyze, anova, export-csv, export-qualifiers, words,
    status, serve, withdraw, export-jspsych, import-jspsych) to the CLI."""
    parser = subparsers.add_parser("study", help="user studies on variant relevance", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="study_command", metavar="STUDY_COMMAND")
    sub.required = True

    def synonyms(p) -> None:
        p.add_argument(
            "--synonyms",
            action="append",
            metavar="FILE",
            help="extra synonym table (JSON, same shape as studies/synonyms.json); repeatable",
        )

    p = sub.add_parser("create", help="create a study database from exploration directories")
    p.add_argument("db", help=f"new SQLite file, or {_URL}")
    p.add_argument("--folder", help=f"with {_URL}: the study's folder, for its pictures (default: here)")
    p.add_argument(
        "--grammar",
        action="append",
        metavar="NAME=DIR",
        required=True,
        help="a grammar and its exploration directory (holding picks.json); repeatable",
    )
    p.add_argument("--name", help="study name (default: the file name)")
    p.add_argument("--budget-minutes", type=float, default=30.0, help="time budget per participant")
    p.add_argument(
        "--config",
        metavar="FILE",
        help="study config JSON: consent, contact, retention, instructions, practice, attention_checks, "
        "demographics, likert, completion_code, framing (defaults for what is left out)",
    )
    p.add_argument("--picture-size", type=int, default=480, help="side of the rendered pictures, pixels (default 480)")
    p.add_argument("--no-render", action="store_true", help="keep the explorations' own pictures (framed each on its own bounds)")
    p.set_defaults(func=run_create)

    p = sub.add_parser("simulate", help="run simulated participants end to end (store, analyse, export)")
    p.add_argument("--participants", type=int, default=20)
    p.add_argument("--grammars", type=int, default=3, help="number of synthetic grammars (without --grammar)")
    p.add_argument("--grammar", action="append", metavar="NAME=DIR", help="use real exploration directories")
    p.add_argument("--tests-per-participant", type=int, help="grammars per participant (default: all)")
    p.add_argument("--noise", type=float, default=0.15, help="perception noise, fraction of the box size")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--name", default="simulated")
    p.add_argument("--db", help="keep the study in this new SQLite file (default: temporary)")
    p.add_argument("-o", "--output", help="write the HTML report to this folder")
    p.add_argument("--store", help="export labelled qualifier points to this SQLite file")
    synonyms(p)
    p.set_defaults(func=run_simulate)

    p = sub.add_parser("analyze", help="write the HTML report and CSVs of a study")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("-o", "--output", required=True, help="report folder")
    p.add_argument("--alpha", type=float, default=0.05)
    p.add_argument("--min-usefulness", default="good", help="groups kept for qualifiers (default: good)")
    p.add_argument("--include-unfinished", action="store_true", help="also analyse unfinished tests")
    p.add_argument("--no-figures", action="store_true", help="tables and CSVs only")
    synonyms(p)
    p.set_defaults(func=run_analyze)

    p = sub.add_parser("anova", help="one-way ANOVA of a table (rows = image points, columns = grammars)")
    p.add_argument("table", help="TSV file, optional header row and row-label column")
    p.add_argument("--alpha", type=float, default=0.05)
    labels = p.add_mutually_exclusive_group()
    labels.add_argument(
        "--row-labels", dest="row_labels", action="store_true", default=None, help="the first column holds row labels"
    )
    labels.add_argument("--no-row-labels", dest="row_labels", action="store_false", help="the first column is data")
    p.set_defaults(func=run_anova)

    p = sub.add_parser("export-csv", help="export the raw answers to CSV files")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("-o", "--output", required=True, help="folder for the CSV files")
    synonyms(p)
    p.set_defaults(func=run_export_csv)

    p = sub.add_parser("export-qualifiers", help="export labelled points to the qualifier store")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("--store", required=True, help="SQLite file holding the qualifier_points table")
    p.add_argument("--min-usefulness", default="good", help="keep groups rated at least this (default: good)")
    p.add_argument("--source", help="source tag (default: study:<study name>)")
    synonyms(p)
    p.set_defaults(func=run_export_qualifiers)

    p = sub.add_parser("words", help="add the study's new qualifier words, with measured directions, to a vocabulary file")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("-o", "--output", required=True, help="vocabulary file (JSON) to create or add to")
    p.add_argument("--min-groups", type=int, default=2, help="groups that must use a word (default: 2)")
    p.add_argument("--grammars-dir", help="folder of the .lsys files the explorations name (default: shipped grammars)")
    synonyms(p)
    p.set_defaults(func=run_words)

    p = sub.add_parser("withdraw", help="a participant withdraws: left out of analyses, or erased with --delete")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("participant", help="participant code, or external id (e.g. a Prolific PID)")
    p.add_argument("--delete", action="store_true", help="erase every answer of the participant")
    p.set_defaults(func=run_withdraw)

    p = sub.add_parser("status", help="participants and tests of a study")
    p.add_argument("db", help=_DB_HELP)
    p.set_defaults(func=run_status)

    p = sub.add_parser("serve", help="serve the participant pages and the researcher's page on the web")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("--folder", help=f"with {_URL}: the study's folder of pictures, if not the one given at creation")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default: this machine only)")
    p.add_argument("--port", type=int, default=8000)
    p.set_defaults(func=run_serve)

    p = sub.add_parser("export-jspsych", help="write the study as a jsPsych experiment (for JATOS or Pavlovia)")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("-o", "--output", required=True, help="folder for the experiment (new, or an earlier export)")
    p.add_argument(
        "--jspsych",
        default=None,
        metavar="DIR_OR_URL",
        help="a local jsPsych package folder to copy in (runs offline), or its URL (default: the unpkg CDN)",
    )
    p.set_defaults(func=run_export_jspsych)

    p = sub.add_parser("import-jspsych", help="import the result file of a jsPsych export (checked first)")
    p.add_argument("db", help=_DB_HELP)
    p.add_argument("results", help="jsPsych data: JSON, JATOS's results file, or CSV")
    p.set_defaults(func=run_import_jspsych)
