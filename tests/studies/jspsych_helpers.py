"""Plays the exported jsPsych page's data format (what ``ramure-task.js`` records), for the import tests."""

from __future__ import annotations

import json
import pathlib
import random
import re


def read_config(folder: pathlib.Path) -> dict:
    """The task settings an export wrote (``window.RAMURE_TASK = {...};``)."""
    text = (folder / "ramure-config.js").read_text(encoding="utf-8")
    return json.loads(re.fullmatch(r"window\.RAMURE_TASK = (.*);\s*", text, re.S).group(1))


def play_run(config: dict, seed: int, external_id: str | None = None, groups_of: int = 4) -> list[dict]:
    """One participant's jsPsych trials: consent, then each stimulus set in a random order, sorted
    into groups of ``groups_of`` consecutive pictures of their shown order, every answer given."""
    rng = random.Random(seed)
    run = f"{rng.getrandbits(64):016x}"
    common = {"ramure_study": config["study"], "ramure_run": run, "external_id": external_id}
    trials = [{"ramure": "consent", "consent": True, "trial_type": "ramure-consent", "trial_index": 0, **common}]
    order = list(range(len(config["sets"])))
    rng.shuffle(order)
    for part, index in enumerate(order, start=1):
        stimulus = config["sets"][index]
        shown = stimulus["pictures"][:]
        rng.shuffle(shown)
        labels = rng.sample([a + d for a in "ABCDEFGHJKLMNPQRSTUVWXYZ" for d in "23456789"], len(shown))
        groups = []
        for start in range(0, len(shown), groups_of):
            pictures = shown[start : start + groups_of]
            several = len(pictures) > 1
            groups.append(
                dict(
                    pictures=pictures,
                    representative=rng.choice(pictures),
                    usefulness=rng.randint(1, 4),
                    difference=rng.randint(1, 4),
                    representative_quality=rng.randint(1, 4) if several else None,
                    words=rng.sample(["small", "dense", "tall", "sparse", "bushy"], rng.randint(1, 2)),
                )
            )
        sorted_ms = rng.randint(20000, 90000)
        trials.append(
            dict(
                ramure="part",
                grammar=stimulus["grammar"],
                part=part,
                parts=len(order),
                shown=[{"picture": c, "label": lab} for c, lab in zip(shown, labels)],
                groups=groups,
                sorted_ms=sorted_ms,
                rt=sorted_ms + rng.randint(30000, 120000),
                trial_type="ramure-part",
                trial_index=part,
                **common,
            )
        )
    return trials


def jspsych_csv(trials: list[dict]) -> str:
    """``jsPsych.data.get().csv()``: every value quoted, objects as JSON text, CRLF lines (its JSON2CSV)."""
    columns: list[str] = []
    for trial in trials:
        columns += [k for k in trial if k not in columns]
    quote = lambda text: '"' + text.replace('"', '""') + '"'  # noqa: E731
    lines = [",".join(quote(c) for c in columns)]
    for trial in trials:
        cells = []
        for column in columns:
            value = trial.get(column, "")
            if isinstance(value, (dict, list)) or value is None:
                value = json.dumps(value, separators=(",", ":"))
            elif isinstance(value, bool):
                value = "true" if value else "false"
            cells.append(quote(str(value)))
        lines.append(",".join(cells))
    return "\r\n".join(lines) + "\r\n"
