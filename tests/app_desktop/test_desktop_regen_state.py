"""The regeneration dock shows a snapshot's state by itself (the window only hands it over)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

pytestmark = pytest.mark.gui


def test_the_regen_dock_shows_constants_rho_and_history_but_not_under_a_held_slider(qtbot):
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.panels.regen import RegenPanel

    make_application()
    panel = RegenPanel()
    snap = SimpleNamespace(constants={"a": 1.5, "b": 2.0}, rho=0.37, can_undo=True, can_redo=False)
    panel.show_state(snap)
    assert list(panel.boxes) == ["a", "b"] and panel.boxes["a"].value() == 1.5
    assert panel.rho.value() == 37 and panel.rho_label.text() == "ρ = 37"
    assert panel.undo_button.isEnabled() and not panel.redo_button.isEnabled()
    panel.rho.setSliderDown(True)  # the user holds the slider: the model's older ρ waits
    panel.show_state(SimpleNamespace(constants={"a": 1.5, "b": 2.0}, rho=0.8, can_undo=False, can_redo=True))
    assert panel.rho.value() == 37 and not panel.undo_button.isEnabled() and panel.redo_button.isEnabled()
