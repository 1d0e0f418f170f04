"""The desktop's 3D view: the plant in a pyvista plotter, its actors, its look and picking.

:mod:`~ramure.app.desktop.view.plant_view` is the main view (click and rubber-band picking,
polished and draft frames); :mod:`~ramure.app.desktop.view.scene` its light, camera, grid and
hairlines; :mod:`~ramure.app.desktop.view.plant_actors` the tubes grouped by thickness;
:mod:`~ramure.app.desktop.view.native_view` a plotter drawn straight into a native X window;
:mod:`~ramure.app.desktop.view.lazy_view` a dock's view made when first on screen and
:mod:`~ramure.app.desktop.view.thumbnails` small QPainter pictures of plants;
:mod:`~ramure.app.desktop.view.presenter` turns the controller's snapshots into the view's
colours, selection and cut preview (the window only connects it).  The view draws
what it is given (a :class:`~ramure.app.desktop.state.Snapshot`, colours, fruit) and reports
picks as Qt signals; it may import Qt, pyvista/VTK, :mod:`ramure.app.desktop.state`,
:mod:`ramure.app.render` and the core packages, and never imports the window, the panels, the
menus or the controller (``tests/app_desktop/test_desktop_rooms.py`` checks it).
"""
