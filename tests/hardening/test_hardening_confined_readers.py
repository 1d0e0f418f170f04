"""Files from strangers read nothing they should not (issue 37, "Reading what it should not").

A grammar reads ``#include`` and ``#surface "FILE"`` files in its own folder and below only; a
session's stored file name is never where files are read from; readers take regular files only
(never a device or a named pipe) and check the size before reading.  Each refusal names the
problem and never shows the content of the file it refused.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal

import pytest

from ramure.app.cli import main
from ramure.errors import GrammarError, RamureError
from ramure.io import FileRefused, read_regular
from ramure.lsys import LSystem
from ramure.lsys.language.grammar import MAX_TEXT_CHARS
from ramure.lsys.regeneration.regen import Session

SECRET = "root:x:0:0:the-secret-line"


@pytest.fixture
def folders(tmp_path):
    """A grammar folder ``plants/`` and, beside it, ``outside/secret.lsys`` holding a secret."""
    plants, outside = tmp_path / "plants", tmp_path / "outside"
    plants.mkdir()
    outside.mkdir()
    (outside / "secret.lsys").write_text(SECRET + "\n")
    return plants, outside


@contextlib.contextmanager
def deadline(seconds=5):
    """Fail, rather than hang, if a reader blocks (a named pipe opened for reading)."""

    def expired(*_):
        raise AssertionError(f"blocked for more than {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def grammar_in(plants, directive):
    main = plants / "main.lsys"
    main.write_text(f"{directive}\nn: 1\nw: F\n")
    return main


@pytest.mark.parametrize(
    "directive",
    [
        '#include "{outside}/secret.lsys"',  # an absolute path elsewhere
        '#include "../outside/secret.lsys"',  # .. out of the folder
        '#include "sub/../../outside/secret.lsys"',
        '#include "link.lsys"',  # a symbolic link out of the folder
        '#surface leak "../outside/secret.lsys"',
        '#surface leak "{outside}/secret.lsys"',
    ],
)
def test_a_file_outside_the_grammars_folder_is_refused_unread(folders, directive):
    plants, outside = folders
    (plants / "sub").mkdir()
    (plants / "link.lsys").symlink_to(outside / "secret.lsys")
    main = grammar_in(plants, directive.format(outside=outside))
    with pytest.raises(GrammarError) as info:
        LSystem.from_file(main)
    assert "outside the grammar's folder" in info.value.message
    assert (info.value.line, info.value.column) == (1, len(directive.split()[0]) + 2 + ("surface" in directive) * 5)
    assert "the-secret-line" not in str(info.value)


def test_a_file_in_the_folder_or_below_is_still_read(folders):
    plants, _ = folders
    (plants / "lib").mkdir()
    (plants / "lib" / "k.lsys").write_text("#define k 3\n")
    main = grammar_in(plants, '#include "lib/k.lsys"')
    assert LSystem.from_file(main).constants == {"k": 3.0}


def test_typed_text_reads_no_file(folders):
    _, outside = folders
    with pytest.raises(GrammarError, match="reads no other file") as info:
        LSystem.from_text(f'#include "{outside}/secret.lsys"\nn: 1\nw: F\n')
    assert "the-secret-line" not in str(info.value)


def test_ramure_check_refuses_an_include_of_etc_passwd_without_printing_it(folders):
    plants, _ = folders
    main = grammar_in(plants, '#include "/etc/passwd"')
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main_cli(["check", str(main)])
    assert rc == 2
    assert "outside the grammar's folder" in err.getvalue()
    assert "root:" not in out.getvalue() + err.getvalue()


def main_cli(argv):
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_an_include_of_a_pipe_or_a_device_is_refused_at_once(folders, kind):
    plants, _ = folders
    special = plants / "special.lsys"
    if kind == "fifo":
        os.mkfifo(special)
    else:  # a link in the folder to /dev/zero (read_regular's own test reads the device itself)
        special = plants / "zero.lsys"
        special.symlink_to("/dev/zero")
    main = grammar_in(plants, f'#include "{special.name}"')
    with deadline(), pytest.raises(GrammarError) as info:
        LSystem.from_file(main)
    expected = "not a regular file" if kind == "fifo" else "outside the grammar's folder"
    assert expected in info.value.message


def test_read_regular_refuses_devices_pipes_folders_and_oversized_files(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    big = tmp_path / "big.txt"
    big.write_bytes(b"x" * 101)
    with deadline():
        for path, reason in (("/dev/zero", "a device"), (fifo, "a named pipe"), (tmp_path, "Is a directory")):
            with pytest.raises(FileRefused, match=reason):
                read_regular(path, 10**6)
    with pytest.raises(FileRefused, match="101 bytes, more than the limit of 100"):
        read_regular(big, 100)
    assert read_regular(big, 101) == b"x" * 101


def test_a_grammar_file_that_is_a_pipe_is_refused(tmp_path):
    fifo = tmp_path / "g.lsys"
    os.mkfifo(fifo)
    with deadline(), pytest.raises(GrammarError, match="not a regular file"):
        LSystem.from_file(fifo)


def test_includes_count_towards_the_grammar_size_limit(folders):
    plants, _ = folders
    half = "// " + "x" * (MAX_TEXT_CHARS // 2) + "\n"
    (plants / "a.lsys").write_text(half)
    (plants / "b.lsys").write_text(half)
    main = plants / "main.lsys"
    main.write_text('#include "a.lsys"\n#include "b.lsys"\nn: 1\nw: F\n')
    with pytest.raises(GrammarError, match="included files have more than") as info:
        LSystem.from_file(main)
    assert info.value.line == 2


def session_data(grammar, filename):
    session = Session(LSystem.from_text("n: 1\nw: F\n"), n=1)
    data = session.to_dict()
    data.update(grammar=grammar, filename=filename)
    return data


@pytest.mark.parametrize(
    "grammar, stored",
    [
        ('#include "secret.lsys"\nn: 1\nw: F\n', "{outside}/plant.lsys"),  # stored name as a base
        ('#include "{outside}/secret.lsys"\nn: 1\nw: F\n', "plant.lsys"),
        ('#surface leak "secret.lsys"\nn: 1\nw: F~leak\n', "{outside}/plant.lsys"),
    ],
)
def test_a_session_reads_no_file_outside_its_own_folder(folders, grammar, stored):
    plants, outside = folders
    data = session_data(grammar.format(outside=outside), stored.format(outside=outside))
    path = plants / "s.json"
    path.write_text(json.dumps(data))
    with pytest.raises(RamureError) as info:
        Session.load(path)
    assert "the-secret-line" not in str(info.value)
    message = str(info.value)
    assert "cannot #include" in message or "no grammar file" in message or "outside" in message


def test_a_session_keeps_its_stored_file_name_and_reads_files_beside_itself(folders):
    plants, outside = folders
    (plants / "k.lsys").write_text("#define k 2\n")
    data = session_data('#include "k.lsys"\nn: 1\nw: F(k)\n', f"{outside}/plant.lsys")
    path = plants / "s.json"
    path.write_text(json.dumps(data))
    session = Session.load(path)
    assert session.filename == f"{outside}/plant.lsys"  # metadata, as saved
    assert session.lsystem.constants == {"k": 2.0}


def test_a_session_file_that_is_a_pipe_is_refused(tmp_path):
    fifo = tmp_path / "s.json"
    os.mkfifo(fifo)
    with deadline(), pytest.raises(RamureError, match="not a regular file"):
        Session.load(fifo)


def test_mtg_and_g3l_readers_refuse_pipes(tmp_path):
    from ramure.gmap.lsystem.g3l import load_g3l
    from ramure.lsys.architecture.mtg import read_mtg

    for name, read in (("p.mtg", read_mtg), ("p.g3l", load_g3l)):
        fifo = tmp_path / name
        os.mkfifo(fifo)
        with deadline(), pytest.raises(RamureError, match="not a regular file"):
            read(fifo)


def test_a_session_whose_plant_cannot_be_drawn_leaves_the_current_plant(tmp_path):
    from ramure.app.model import Explorer

    path = tmp_path / "s.json"
    path.write_text(json.dumps(session_data("n: 0\nw: F(1e300)\n", "plant.lsys")))
    ex = Explorer("grammars/algae.lsys", n=3)
    text, segments, version = ex.text, len(ex.skeleton), ex.version
    with pytest.raises(RamureError, match="not finite"):
        ex.load_session(path)
    assert (ex.text, ex.version) == (text, version)
    assert len(ex.skeleton) == segments


def test_mutated_mtg_files_raise_only_mtg_errors():
    """Random edits of a written MTG (a broken events header, '/I1' for '^/I1', cut lines...)
    are refused with an MTGError naming the line, never a JSONDecodeError or a KeyError."""
    import numpy as np

    import ramure
    from ramure.lsys.architecture.amap import architecture
    from ramure.lsys.architecture.mtg import MTGError, mtg_text, parse_mtg

    text = mtg_text(architecture(ramure.derive("amap/massart", n=3)))
    with pytest.raises(MTGError, match="line 1: the '# ramure-events:' header is not valid JSON"):
        parse_mtg(text.replace("{", "{[", 1))
    starts = [i for i in range(len(text)) if text.startswith("^/I1", i)]
    for at in starts:  # each '^/I1' written as '/I1' in turn: read, or refused (a KeyError once)
        with contextlib.suppress(MTGError):
            parse_mtg(text[:at] + text[at + 1 :])
    rng = np.random.default_rng(37)
    alphabet = list('^/<+IUSAP1{}[]":,\t\n -0')
    refused = 0
    for _ in range(400):
        chars = list(text)
        for at in rng.integers(0, len(chars), rng.integers(1, 4)):
            chars[at] = alphabet[rng.integers(len(alphabet))]
        try:
            parse_mtg("".join(chars))
        except MTGError:
            refused += 1
    assert refused > 100  # the mutations reach the readers' checks


def test_an_error_in_a_surface_file_is_reported_when_the_grammar_is_read(folders):
    plants, _ = folders
    (plants / "blade.lsys").write_text("n: 0\nw: {.f.+f.\np:\n A -> ((\n")
    main = grammar_in(plants, '#surface blade "blade.lsys"')
    with pytest.raises(GrammarError, match=r"#surface blade: blade.lsys, line \d+") as info:
        LSystem.from_file(main)  # parsing only: nothing is derived
    assert info.value.line == 1
