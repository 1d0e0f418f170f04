"""A whole remote participant session in headless Chromium against ``ramure study serve``.

The server runs as the researcher starts it (``ramure study serve STUDY --port N``, a separate
process on 127.0.0.1); Debian's ``/usr/bin/chromium`` is driven by Playwright's Python package
(no browser download), as the notebook's browser test does.  The participant arrives from a
recruiting link, consents, reads the instructions and the practice page, drags pictures into
groups with the mouse, moves others by keyboard and by select-then-"Move here", chooses
representatives, rates and names the groups, reloads the page in the middle and continues,
double-clicks "Finish this part" (the second click is dropped, not sent), answers the attention
check, does the second set, answers the demographics questions and gets a completion code.  Then the database holds every
answer, and the researcher's page shows the participant and downloads the CSVs.  A phone-sized
touch context moves a picture by taps.  Select it alone with ``pytest -m browser``.
"""

from __future__ import annotations

import io
import json
import os
import pathlib
import socket
import subprocess
import sys
import time
import urllib.request
import zipfile

import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")
sync_api = pytest.importorskip("playwright.sync_api")

from web_helpers import make_study  # noqa: E402

from ramure.studies.storage import Study  # noqa: E402

pytestmark = [pytest.mark.browser, pytest.mark.timeout(300)]

CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]
ARTIFACTS = pathlib.Path(__file__).resolve().parents[1] / "artifacts" / "browser"
IDLE = "() => !document.getElementById('app').classList.contains('busy')"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def served(tmp_path):
    """``ramure study serve`` on a two-part study; yields (db, the addresses it printed)."""
    db = make_study(tmp_path)
    port = free_port()
    ramure = pathlib.Path(sys.executable).with_name("ramure")
    log = open(tmp_path / "serve.log", "wb")
    process = subprocess.Popen(
        [str(ramure), "study", "serve", str(db), "--port", str(port)], stdout=subprocess.PIPE, stderr=log, text=True
    )
    lines = []
    while not lines or lines[-1] != "}\n":
        line = process.stdout.readline()
        assert line, (tmp_path / "serve.log").read_text()
        lines.append(line)
    addresses = json.loads("".join(lines))
    deadline = time.monotonic() + 30
    while True:
        try:
            urllib.request.urlopen(addresses["participants"], timeout=2).read()
            break
        except OSError:
            assert time.monotonic() < deadline and process.poll() is None, (tmp_path / "serve.log").read_text()
            time.sleep(0.1)
    yield db, addresses
    process.terminate()
    process.wait(timeout=30)
    log.close()


def act(page, do):
    """Do one participant action and wait until the server acknowledged it."""
    do()
    page.wait_for_function(IDLE, timeout=15_000)


def drag(page, source, target):
    """A real mouse drag (pointer events) from the centre of ``source`` to the centre of ``target``."""
    a, b = source.bounding_box(), target.bounding_box()
    page.mouse.move(a["x"] + a["width"] / 2, a["y"] + a["height"] / 2)
    page.mouse.down()
    page.mouse.move(a["x"] + a["width"] / 2 + 12, a["y"] + a["height"] / 2 + 12, steps=3)
    page.mouse.move(b["x"] + b["width"] / 2, b["y"] + b["height"] / 2, steps=8)
    page.mouse.up()
    page.wait_for_function(IDLE, timeout=15_000)


def pool(page):
    return page.locator("[data-zone=pool] .pic")


def answer_groups(page, words, first=1):
    """Choose the representative of groups ``first``.. , answer their questions and name them ``words``."""
    for label, word in enumerate(words, start=first):
        if page.locator(f"[data-zone='{label}'] .pic").count() > 1:
            act(page, page.locator(f"input[name=rep-{label}]").first.check)
            act(page, page.locator(f"input[name=representative_quality-{label}][value='3']").check)
        act(page, page.locator(f"input[name=usefulness-{label}][value='{1 + label % 4}']").check)
        act(page, page.locator(f"input[name=difference-{label}][value='2']").check)
        page.locator(f"[data-key=word-{label}]").fill(word)
        act(page, lambda: page.locator(f"[data-key=word-{label}]").press("Enter"))  # noqa: B023 (called at once)


def test_a_remote_participant_session_in_chromium(served):
    if not os.access(CHROMIUM, os.X_OK):
        pytest.skip("Debian's chromium is not installed")
    db, addresses = served
    base = addresses["participants"]
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 1000})
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(base + "?PROLIFIC_PID=5f3a9c0b7d")
            assert page.locator("#start").is_disabled()
            page.check("#agree")
            page.click("#start")
            for title in ("Instructions", "Practice"):  # the study's pages before the first set
                page.wait_for_selector(f"h1:text-is('{title}')")
                act(page, lambda: page.click("#continue-page"))
            page.wait_for_selector("text=Set 1 of 2")
            assert pool(page).count() == 27
            assert page.evaluate("() => Array.from(document.images).filter(i => i.complete && i.naturalWidth === 0).length") == 0

            # Part 1: two groups started by mouse drags, one picture dropped onto group 1.
            drag(page, pool(page).first, page.locator("[data-zone=new]"))
            drag(page, pool(page).first, page.locator("[data-zone=new]"))
            drag(page, pool(page).first, page.locator("[data-zone='1']"))
            assert page.locator("[data-zone='1'] .pic").count() == 2 and pool(page).count() == 24
            # Select a picture, then "Move here" on group 2 (keyboard and touch friendly).
            act(page, lambda: pool(page).first.click())
            act(page, lambda: page.locator("[data-zone='2'] .move").click())
            assert page.locator("[data-zone='2'] .pic").count() == 2
            # Keys: 1 and 2 move the focused picture into those groups.
            for key in "1" * 12 + "2" * 10:
                act(page, lambda: pool(page).first.press(key))  # noqa: B023 (called at once)
            assert page.locator("[data-zone='1'] .pic").count() == 14 and page.locator("[data-zone='2'] .pic").count() == 12
            # The last one alone, then answer group 1 only and reload in the middle.
            act(page, lambda: pool(page).first.press("n"))
            answer_groups(page, ["tall and thin"])
            page.reload()
            page.wait_for_selector("text=Set 1 of 2")
            assert page.locator("[data-zone='1'] li").first.inner_text().startswith("tall and thin")
            assert page.locator("input[name=usefulness-1][value='2']").is_checked()
            assert pool(page).count() == 0 and page.locator(".group").count() == 3
            ARTIFACTS.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(ARTIFACTS / "study_web_desktop.png"), full_page=True)
            answer_groups(page, ["bushy", "odd one"], first=2)
            assert page.locator(".missing").count() == 0
            page.locator("#finish").dblclick()
            page.wait_for_selector("#continue-page")
            page.wait_for_function(IDLE)
            assert "A few questions" in page.inner_text("#app")  # the attention check after the first set
            assert page.inner_text("#notice") == "Saved."  # the second click was dropped, not sent and refused
            page.check("input[name=attention_1][value=fair]")
            act(page, lambda: page.click("#continue-page"))

            # Set 2: everything into one group by keys.
            page.wait_for_selector("text=Set 2 of 2")
            act(page, lambda: pool(page).first.press("n"))
            while pool(page).count():
                act(page, lambda: pool(page).first.press("1"))
            answer_groups(page, ["all alike"])
            act(page, lambda: page.click("#finish"))
            page.wait_for_selector("h1:text-is('About you')")
            act(page, lambda: page.click("#continue-page"))  # nothing chosen: refused in one line
            assert "please answer" in page.inner_text("#notice")
            page.check("input[name=age][value='25-39']")
            page.check("input[name=expertise][value='a little']")
            act(page, lambda: page.click("#continue-page"))
            code = page.locator("#completion").inner_text()
            assert len(code) >= 6 and code.isalnum()
            page.reload()
            assert page.locator("#completion").inner_text() == code  # the end survives a reload too
            assert errors == []

            # A phone: touch taps select a picture and move it.
            phone = browser.new_context(viewport={"width": 390, "height": 844}, has_touch=True, is_mobile=True)
            mobile = phone.new_page()
            mobile.goto(base)
            mobile.tap("#agree")
            mobile.tap("#start")
            for title in ("Instructions", "Practice"):
                mobile.wait_for_selector(f"h1:text-is('{title}')")
                act(mobile, lambda: mobile.tap("#continue-page"))
            mobile.wait_for_selector("text=Set 1 of 2")
            mobile.locator("[data-zone=pool] .pic").first.tap()
            act(mobile, lambda: mobile.locator("[data-zone=new] .move").tap())
            assert mobile.locator("[data-zone='1'] .pic").count() == 1
            mobile.screenshot(path=str(ARTIFACTS / "study_web_phone.png"))
            phone.close()

            # The researcher's page: both participants, one finished; the CSV download.
            researcher = browser.new_page(accept_downloads=True)
            researcher.goto(addresses["researcher"])
            researcher.wait_for_selector("#people tbody tr >> nth=1")
            row = researcher.locator("#people tbody tr").first
            assert row.locator("td").all_inner_texts()[:4] == ["P101", "yes", "2", "2"]
            assert "2 participants, 2 of 3 parts finished" in researcher.inner_text("#summary")
            with researcher.expect_download() as download:
                researcher.click("#download")
            with zipfile.ZipFile(io.BytesIO(pathlib.Path(download.value.path()).read_bytes())) as zf:
                groups = zf.read("groups.csv").decode()
            assert groups.count("P101,") == 3 + 1 and groups.count("P102,") == 1
            wrong = browser.new_page()
            wrong.goto(addresses["researcher"].split("#")[0] + "#not-the-token")
            wrong.wait_for_selector("text=Cannot read the progress")
        finally:
            browser.close()

    with Study.open(db, readonly=True) as study:
        assert study.finished("P101", "g0") and study.finished("P101", "g1")
        rows = study.conn.execute(
            "SELECT gr.name, g.label, count(gi.pick_id), g.usefulness, g.difference, g.representative_quality, "
            "(SELECT group_concat(text, '|') FROM qualifiers q WHERE q.group_id = g.id) FROM groups g "
            "JOIN tests t ON t.id = g.test_id JOIN participants p ON p.id = t.participant_id "
            "JOIN grammars gr ON gr.id = t.grammar_id JOIN group_images gi ON gi.group_id = g.id "
            "WHERE p.code = 'P101' GROUP BY g.id ORDER BY gr.name, g.label"
        ).fetchall()
        assert rows == [
            ("g0", 1, 14, 2, 2, 3, "tall and thin"),
            ("g0", 2, 12, 3, 2, 3, "bushy"),
            ("g0", 3, 1, 4, 2, None, "odd one"),
            ("g1", 1, 27, 2, 2, 3, "all alike"),
        ]
        external = [e["detail"] for e in study.events("P101") if e["action"] == "external_id"]
        assert external == [{"external_id": "5f3a9c0b7d"}]
        finishes = [e for e in study.events("P101") if e["action"] == "finish"]
        assert len(finishes) == 2  # the double click finished part 1 once
