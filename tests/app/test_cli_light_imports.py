"""Commands that do little load little: each runs in a fresh interpreter and the heavy
libraries it has no use for must still be absent from ``sys.modules`` afterwards.

``ramure study anova`` of six numbers used to import all of :mod:`ramure.studies` (the
report's metrics, matplotlib, scipy.stats: 1.7 s of CPU for 0.3 s of work)."""

from __future__ import annotations

import json
import subprocess
import sys

TABLE = "group\tvalue\na\t1\na\t2\na\t3\nb\t4\nb\t5\nb\t7\n"
ROWS = "image\tg1\tg2\tg3\n1\t1\t2\t3\n2\t2\t3\t5\n3\t1\t2\t4\n4\t2\t3\t3\n"


def _loaded_after(argv: list[str], cwd, heavy: tuple[str, ...]) -> tuple[list[str], str]:
    """The modules of ``heavy`` loaded after ``ramure argv`` and what the command printed."""
    probe = (
        "import sys, json\nfrom ramure.app.cli import main\n"
        f"code = main({argv!r})\n"
        f"print(json.dumps([code, [m for m in {heavy!r} if m in sys.modules]]))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, cwd=cwd)
    *printed, last = done.stdout.splitlines()
    code, loaded = json.loads(last)
    assert code == 0, done.stderr
    return loaded, "\n".join(printed)


def test_anova_loads_neither_scipy_stats_nor_the_report(tmp_path):
    (tmp_path / "table.tsv").write_text(ROWS, encoding="utf-8")
    heavy = ("scipy.stats", "matplotlib", "ramure.metrics", "ramure.studies.report", "ramure.lsys", "numba")
    loaded, printed = _loaded_after(["study", "anova", "table.tsv"], tmp_path, heavy)
    assert loaded == []
    answer = json.loads(printed)
    # The same F, F_crit and p as scipy.stats.f (whose sf and ppf are the special functions used).
    from scipy import stats

    across = answer["across_grammars"]
    assert (across["df_between"], across["df_within"]) == (2, 9)
    assert across["F_crit"] == float(stats.f.ppf(0.95, 2, 9))
    assert across["p"] == float(stats.f.sf(across["F"], 2, 9))
    assert across["significant"] is True


def test_importing_the_studies_package_is_lazy_but_complete():
    probe = (
        "import sys, ramure.studies as s\nbefore = 'ramure.studies.report' in sys.modules\n"
        "names = [getattr(s, n).__name__ for n in ('write_report', 'Study', 'one_way_anova')]\n"
        "print(before, names, sorted(set(s.__all__) - set(dir(s))))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "['write_report',", "'Study',", "'one_way_anova']", "[]"]


def test_rendering_skips_pyvista_display_probe(tmp_path):
    # pyvista's first Plotter ran `xset -q` and a test render only to decide on a warning
    # that cannot fire once headless_setup has run; the picture must still be drawn.
    probe = (
        "import subprocess, pyvista.plotting.tools as tools\n"
        "calls = []\n"
        "real = subprocess.Popen\n"
        "subprocess.Popen = lambda *a, **k: calls.append(a) or real(*a, **k)\n"
        "tools.supports_open_gl = lambda: calls.append('gl') or True\n"
        "from ramure.app.cli import main\n"
        "code = main(['render', 'honda_sympodial', '-n', '4', '-o', 'p.png', '--size', '64x64'])\n"
        "print(code, len(calls))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert done.stdout.split()[-2:] == ["0", "0"], done.stdout + done.stderr
    import numpy as np
    from PIL import Image

    pixels = np.asarray(Image.open(tmp_path / "p.png").convert("RGB")).reshape(-1, 3)
    assert len(pixels) == 64 * 64
    assert len(np.unique(pixels, axis=0)) > 1  # not a blank picture


def test_fruit_facts_without_a_file_load_no_pyvista(tmp_path):
    heavy = ("pyvista", "vtkmodules", "matplotlib")
    loaded, printed = _loaded_after(["fruit", "--preset", "round_tomato", "--json"], tmp_path, heavy)
    assert loaded == []
    facts = json.loads(printed)
    assert (facts["volumes"], facts["valid"]) == (110, True)
    assert "output" not in facts


def test_fruit_grid_file_still_written(tmp_path):
    loaded, printed = _loaded_after(["fruit", "--preset", "round_tomato", "--json", "-o", "t.vtu"], tmp_path, ("pyvista",))
    assert loaded == ["pyvista"]
    import pyvista as pv

    grid = pv.read(tmp_path / "t.vtu")
    assert grid.n_cells == json.loads(printed)["volumes"] == 110
