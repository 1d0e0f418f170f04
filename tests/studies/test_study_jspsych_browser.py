"""The exported jsPsych experiment in headless Chromium from file://, then its download imported.

jsPsych is not shipped with Ramure: this test needs a local copy of the jsPsych package (the
folder ``node_modules/jspsych`` of ``npm install jspsych@8.3.0``) named by ``RAMURE_JSPSYCH``,
and is skipped without it (nothing is fetched from the network).  Debian's Chromium is driven by
Playwright's Python package, as the other browser tests do.  A participant consents, sorts with
clicks and with the keyboard, moves a picture between groups, answers every group of both parts,
downloads the answers; ``import_jspsych`` then stores them and the database holds every group.
"""

from __future__ import annotations

import json
import os
import pathlib

import pytest

sync_api = pytest.importorskip("playwright.sync_api")

from jspsych_helpers import read_config  # noqa: E402
from web_helpers import make_study  # noqa: E402

from ramure.studies.jspsych import export_jspsych, import_jspsych  # noqa: E402
from ramure.studies.storage import Study  # noqa: E402

pytestmark = [pytest.mark.browser, pytest.mark.timeout(300)]

CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]
JSPSYCH = os.environ.get("RAMURE_JSPSYCH")


def _answer_part(page, groups_of: int) -> None:
    page.wait_for_selector("#ramure-pool .ramure-pic")
    first = page.locator("#ramure-pool .ramure-pic").first
    first.focus()
    page.keyboard.press("Space")  # the keyboard selects as well as a click
    assert page.locator("#ramure-pool .ramure-pic.selected").count() == 1
    while page.locator("#ramure-pool .ramure-pic").count():
        pool = page.locator("#ramure-pool .ramure-pic:not(.selected)")
        for _ in range(min(groups_of - page.locator("#ramure-pool .ramure-pic.selected").count(), pool.count())):
            page.locator("#ramure-pool .ramure-pic:not(.selected)").first.click()
        page.click("#ramure-new-group")
    groups = page.locator("fieldset.ramure-group")
    assert groups.count() == -(-27 // groups_of)
    groups.nth(0).locator(".ramure-pic").first.click()  # one picture of group 1 moves to group 2
    groups.nth(1).locator(".ramure-move").click()
    assert page.locator("fieldset.ramure-group").nth(1).locator(".ramure-pic").count() == groups_of + 1
    page.click("#ramure-sorted")
    while True:
        page.wait_for_selector("#ramure-next")
        pictures = page.locator(".ramure-group .ramure-pic")
        if pictures.count() > 1:
            pictures.nth(1).click()
        for question, level in (("usefulness", 3), ("difference", 2), ("representative_quality", 4)):
            choice = page.locator(f"[data-question={question}] input[value='{level}']")
            if choice.count():
                choice.check()
        page.fill("#ramure-words", "dense, tall")
        last = page.inner_text("#ramure-next") == "Finish this part"
        page.click("#ramure-next")
        if last:
            return


@pytest.mark.skipif(not JSPSYCH or not pathlib.Path(JSPSYCH, "dist").is_dir(), reason="no local jsPsych copy (RAMURE_JSPSYCH)")
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed")
def test_exported_experiment_runs_in_chromium_and_its_download_imports(tmp_path):
    db = make_study(tmp_path / "study", grammars=2)
    folder = tmp_path / "experiment"
    export_jspsych(db, folder, jspsych=JSPSYCH)
    config = read_config(folder)
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            context = browser.new_context(accept_downloads=True)
            page = context.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.goto((folder / "index.html").as_uri() + "?PROLIFIC_PID=abc123")
            page.check("#ramure-agree")
            page.click("#ramure-start")
            _answer_part(page, groups_of=9)
            assert "Part 2 of 2" in page.inner_text(".ramure-progress")
            _answer_part(page, groups_of=6)
            page.wait_for_selector("#ramure-code")
            assert page.inner_text("#ramure-code") == config["completion_code"]
            with page.expect_download() as download:
                page.click("#ramure-download")
            results = tmp_path / "ramure-results.json"
            download.value.save_as(results)
            assert errors == []
        finally:
            browser.close()
    trials = json.loads(results.read_text())
    assert [t.get("ramure") for t in trials] == ["consent", "part", "part"]
    summary = import_jspsych(db, results)
    assert summary["participants"] == ["P101"] and summary["tests"] == 2
    with Study.open(db, readonly=True) as study:
        assert [p["finished"] for p in study.participants()] == [2]
        words = study.conn.execute("SELECT count(*), count(DISTINCT text) FROM qualifiers").fetchone()
        groups = study.conn.execute("SELECT count(*) FROM groups").fetchone()[0]
        assert groups == 3 + 5 and words == (2 * groups, 2)  # parts of 9s (3 groups) and 6s (5 groups)
        externals = [e["detail"]["external_id"] for e in study.events() if e["action"] == "external_id"]
        assert externals == ["abc123"]
