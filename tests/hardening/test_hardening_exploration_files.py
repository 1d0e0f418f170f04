"""Exploration folders from strangers (issue 37, items 4 and 7): ``pca.json`` names a grammar only
among the shipped grammars or inside the folder, and a value of the wrong type is one clear line."""

from __future__ import annotations

import json
import os

import pytest

from ramure.errors import RamureError
from ramure.metrics.exploration import find_grammar, read_exploration_info

HONDA = "n: 2\nw: A\np:\n  A -> F[+A]A\n"


@pytest.fixture
def folders(tmp_path):
    """``explore/`` (the exploration) beside ``outside/evil.lsys`` (a grammar it must not reach)."""
    (tmp_path / "explore").mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "evil.lsys").write_text(HONDA)
    return tmp_path


def write_pca(folder, doc):
    (folder / "pca.json").write_text(json.dumps(doc) if not isinstance(doc, str) else doc)


@pytest.mark.parametrize("name", ["../outside/evil", "../outside/evil.lsys", "/etc/passwd", "~/evil", "..\\outside\\evil"])
def test_a_grammar_outside_the_folders_is_refused(folders, name):
    write_pca(folders / "explore", {"grammar": name, "n": 2})
    with pytest.raises(RamureError, match="not a grammar name"):
        read_exploration_info(folders / "explore")


def test_a_link_out_of_the_exploration_folder_is_not_followed(folders):
    os.symlink(folders / "outside" / "evil.lsys", folders / "explore" / "evil.lsys")
    write_pca(folders / "explore", {"grammar": "evil"})
    assert read_exploration_info(folders / "explore").grammar_file is None


def test_shipped_names_and_files_inside_the_folder_are_found(folders):
    explore = folders / "explore"
    write_pca(explore, {"grammar": "amap/rauh", "n": 4, "seed": 7})
    info = read_exploration_info(explore)
    assert (info.name, info.grammar_file.name, info.n, info.seed) == ("amap/rauh", "rauh.lsys", 4, 7)
    (explore / "mine.lsys").write_text(HONDA)
    write_pca(explore, {"grammar": "mine", "n": None, "seed": None})
    info = read_exploration_info(explore)
    assert (info.grammar_file, info.n, info.seed) == ((explore / "mine.lsys").resolve(), None, 0)
    (explore / "pca.json").unlink()
    assert read_exploration_info(explore) == read_exploration_info(explore, name="explore")
    assert read_exploration_info(explore).name == "explore" and read_exploration_info(explore).grammar_file is None
    assert find_grammar("evil", grammars_dir=folders / "outside") == (folders / "outside" / "evil.lsys").resolve()


@pytest.mark.parametrize(
    "doc, words",
    [
        ({"grammar": 5}, "'grammar' must be a grammar name (text), not 5"),
        ({"grammar": ["honda"]}, "'grammar' must be a grammar name"),
        ({"grammar": ""}, "'grammar' must be a grammar name"),
        ({"n": "3"}, "'n' must be an integer from 0 to 1000, not '3'"),
        ({"n": True}, "'n' must be an integer"),
        ({"n": 2.5}, "'n' must be an integer"),
        ({"n": 10**9}, "'n' must be an integer from 0 to 1000"),
        ({"seed": "abc"}, "'seed' must be an integer, not 'abc'"),
        ({"seed": {"a": 1}}, "'seed' must be an integer"),
        ([1, 2], "expected a JSON object, not list"),
        ("{not json", "not valid JSON"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ],
)
def test_values_of_the_wrong_type_are_refused_in_one_line(folders, doc, words):
    write_pca(folders / "explore", doc)
    with pytest.raises(RamureError) as info:
        read_exploration_info(folders / "explore")
    assert words in str(info.value) and "\n" not in str(info.value) and "pca.json" in str(info.value)


def test_non_utf8_pipes_and_devices_are_refused(folders):
    explore = folders / "explore"
    (explore / "pca.json").write_bytes(b'{"grammar": "\xff"}')
    with pytest.raises(RamureError, match="not UTF-8"):
        read_exploration_info(explore)
    (explore / "pca.json").unlink()
    os.mkfifo(explore / "pca.json")  # no writer: a plain open would block for good
    with pytest.raises(RamureError, match="named pipe"):
        read_exploration_info(explore)


@pytest.mark.parametrize(
    "content, words", [(b"\xff\xfe[]", "not UTF-8"), (b"[" * 100_000, "nested too deeply"), (None, "named pipe")]
)
def test_picks_json_is_read_as_a_bounded_regular_utf8_file(tmp_path, content, words):
    from ramure.studies.picks import load_picks

    if content is None:
        os.mkfifo(tmp_path / "picks.json")
    else:
        (tmp_path / "picks.json").write_bytes(content)
    with pytest.raises(RamureError, match=words):
        load_picks(tmp_path)
