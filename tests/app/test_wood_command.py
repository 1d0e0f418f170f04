"""``ramure wood`` details found by type-checking: the legend's box, ``--set`` names."""

import pytest

from ramure.app.cli import main

pv = pytest.importorskip("pyvista")


def test_wood_legend_is_drawn_on_a_light_box():
    # a type-check fix had commented ``bcolor`` out of the add_legend call
    from ramure.app.commands.wood import add_wood_actors, legend_for
    from ramure.app.render import headless_setup

    headless_setup()
    grid = pv.ImageData(dimensions=(3, 3, 3)).cast_to_unstructured_grid()
    grid.cell_data["rgb"] = [[120, 80, 40]] * grid.n_cells
    plotter = pv.Plotter(off_screen=True, window_size=(200, 200))
    try:
        surface = add_wood_actors(plotter, grid, legend_for("oak"))
        assert surface.n_cells == 6 * 4  # the cube's outer faces, 2x2 per side
        assert plotter.legend.GetUseBackground()
        assert plotter.legend.GetBackgroundColor() == pytest.approx((0.96, 0.96, 0.94), abs=1 / 255)
        # pith, heartwood and sapwood early/late, inner bark, ridges, fissures, knot, tension wood
        assert plotter.legend.GetNumberOfEntries() == 10
        assert plotter.legend.GetEntryTextProperty().GetColor() == pytest.approx((0.08, 0.08, 0.08))
        assert plotter.legend.GetEntryIcon(3).GetPointData().GetScalars().GetTuple3(0) == (234, 214, 173)  # oak sapwood
    finally:
        plotter.close()


@pytest.mark.parametrize("pair", ["seed=3", "species=oak", "check_every_step=0", "branch_seeds=0", "max_branches=2"])
@pytest.mark.parametrize("source", [[], ["--from-plant", "honda_sympodial", "-n", "2"]])
def test_set_refuses_names_that_are_not_wood_parameters(capsys, pair, source):
    # these used to reach grow_wood/from_skeleton as keyword arguments: a TypeError traceback
    assert main(["wood", "--years", "2", *source, "--set", pair, "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"unknown wood parameter '{pair.split('=')[0]}'" in err and "sapwood_rings" in err


def test_set_still_takes_a_wood_parameter(capsys):
    import json

    assert main(["wood", "--years", "2", "--set", "branches=0", "--set", "sides=5", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    from ramure.gmap.organs import wood as W

    assert record["valid"] and record["volumes"] == W.trunk_volumes(5, 2)
    assert record["tissues"]["bark"] == 5 * 2 * 3 // 2  # s Y (Y + 1) / 2 bark cells, as in tests/gmap
