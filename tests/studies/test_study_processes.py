"""Several processes on one study lose no acknowledged answer (issue 38, section 1).

On POSIX, closing any descriptor of a file drops every lock the process holds on it,
including those of its open SQLite connections.  If opening a study read the header
with a plain ``open()``, a second ``Study.open`` in a process left its first connection
unlocked: another process closing the study then checkpointed and deleted the WAL the
first one was still writing into, and its later answers went to a deleted file.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import textwrap

from ramure.studies.picks import lattice_picks
from ramure.studies.storage import Study, is_database_file

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ENV = dict(os.environ, PYTHONPATH=ROOT)

# What `ramure study status` does: open, read, close (the last closer checkpoints);
# then it prints every qualifier it finds.
READER = textwrap.dedent("""
    import sys
    from ramure.studies.storage import Study
    for _ in range(int(sys.argv[2])):
        with Study.open(sys.argv[1]) as study:
            study.participants(), study.tests()
            words = [t for (t,) in study.conn.execute("SELECT text FROM qualifiers ORDER BY id")]
    print(" ".join(words), flush=True)
""")


def read_elsewhere(db, times=1):
    """The qualifiers another process sees after opening the study ``times`` times."""
    command = [sys.executable, "-c", READER, str(db), str(times)]
    reader = subprocess.run(command, env=ENV, cwd=ROOT, capture_output=True, text=True)
    assert reader.returncode == 0, reader.stderr
    return reader.stdout.split()


# A participant's station: one study open for the whole test, and a second `Study.open`
# in the same process now and then (the desktop's picture worker, the analyst window, a
# re-run notebook cell).  Each answer is printed once committed: acknowledged.
WRITER = textwrap.dedent("""
    import sys
    from ramure.studies.storage import Study
    db, code, answers = sys.argv[1], sys.argv[2], int(sys.argv[3])
    study = Study.open(db)
    s = study.session(code, "honda")
    s.set_groups([list(range(1, 28))])
    for i in range(answers):
        if i % 4 == 0:
            Study.open(db).close()
        s.add_qualifier(1, f"{code}-{i}")
        print(f"{code}-{i}", flush=True)
    study.close()
""")


def start(script, *args):
    return subprocess.Popen([sys.executable, "-c", script, *map(str, args)], stdout=subprocess.PIPE, text=True, env=ENV, cwd=ROOT)


def make_study(path, codes):
    with Study.create(path, grammars={"honda": lattice_picks(seed=1)}) as study:
        for code in codes:
            study.add_participant(code, consent=True)


def stored_qualifiers(path):
    with Study.open(path) as study:
        assert study.conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        return {text for (text,) in study.conn.execute("SELECT text FROM qualifiers")}


def test_a_second_open_then_another_reader_loses_nothing(tmp_path):
    db = tmp_path / "study.db"
    make_study(db, ["P1"])
    study = Study.open(db)
    s = study.session("P1", "honda")
    s.set_groups([list(range(1, 28))])
    s.add_qualifier(1, "before")
    Study.open(db).close()  # a second open in this process, as the picture worker does
    assert read_elsewhere(db) == ["before"]  # `ramure study status` meanwhile
    s.add_qualifier(1, "after")  # acknowledged: committed without error
    # Seen by every other process while this one still runs (or crashes now).
    assert read_elsewhere(db) == ["before", "after"]
    study.close()
    assert stored_qualifiers(db) == {"before", "after"}


def test_three_writers_a_reader_and_kill_9_lose_no_acknowledged_answer(tmp_path):
    db = tmp_path / "study.db"
    codes = ["P1", "P2", "P3"]
    make_study(db, codes)
    answers = 40
    writers = {code: start(WRITER, db, code, answers) for code in codes}
    reader = start(READER, db, 60)
    acknowledged: dict[str, list[str]] = {code: [] for code in codes}
    try:
        # P2 is killed -9 in the middle of its test, while the others write and read.
        for line in writers["P2"].stdout:
            acknowledged["P2"].append(line.strip())
            if len(acknowledged["P2"]) == answers // 2:
                os.kill(writers["P2"].pid, signal.SIGKILL)
                break
        for code in ("P1", "P3"):
            acknowledged[code] = [line.strip() for line in writers[code].stdout]
        reader.stdout.read()
    finally:
        for proc in [*writers.values(), reader]:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    assert writers["P2"].returncode == -signal.SIGKILL
    assert writers["P1"].returncode == writers["P3"].returncode == reader.returncode == 0
    assert len(acknowledged["P1"]) == len(acknowledged["P3"]) == answers
    stored = stored_qualifiers(db)
    for code in codes:
        missing = [text for text in acknowledged[code] if text not in stored]
        assert not missing, f"{code}: acknowledged but lost: {missing}"
    # P2 may have committed one more answer than it could announce, never fewer.
    assert len({t for t in stored if t.startswith("P2-")}) in (answers // 2, answers // 2 + 1)


def test_a_picture_naming_the_database_is_never_shown(tmp_path):
    """Showing it would open the database with a plain descriptor (and drop our locks)."""
    db = tmp_path / "study.db"
    (tmp_path / "pic.png").write_bytes(b"png")
    (tmp_path / "alias.db").hardlink_to(tmp_path / "pic.png")
    names = ["study.db", "study.db-wal", "./study.db-shm", "pic.png"]
    picks = [dataclasses.replace(p, image=names[i % 4]) for i, p in enumerate(lattice_picks(seed=1))]
    with Study.create(db, grammars={"honda": picks}) as study:
        shown = [p.image for p in study.picks("honda")]
        assert shown[:4] == [None, None, None, str(tmp_path / "pic.png")]
        assert sum(image is not None for image in shown) == 6  # picks 4, 8, ..., 24
        assert is_database_file(db, tmp_path / "study.db-wal")
        assert not is_database_file(db, tmp_path / "pic.png")
        assert not is_database_file(tmp_path / "alias.db", tmp_path / "study.db")
        assert is_database_file(tmp_path / "alias.db", tmp_path / "pic.png")  # the same file, linked
