"""``ramure crack``: carve a crack drawn from a skeleton and a profile into a closed surface.

    ramure crack --on stone --nodes 63 --seed 0 --noise 12 --json -o cracked.png
    ramure crack --on vase.stl --from-plant honda_sympodial -n 5 --t 0.8 -o vase_cracked.stl
"""
from __future__ import annotations

import json
import time

from ramure.app.cli import UserError
from ramure.app.commands.lichen import substrate
from ramure.app.commands.plant import output_file, parse_size
from ramure.gmap.cracks import add_noise, carve, pattern_from_skeleton, random_pattern, smooth, symmetric


def _vector(text, option):
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise UserError(f"{option} expects X,Y,Z, got '{text}'") from None
    if len(values) != 3:
        raise UserError(f"{option} expects X,Y,Z, got '{text}'")
    return values


def _pattern(args):
    if args.nodes < 2:
        raise UserError(f"--nodes must be >= 2, not {args.nodes}")
    if args.from_plant:
        from ramure.lsys import LSystem

        skeleton = LSystem.from_file(args.from_plant).derive(n=args.n, seed=args.seed).skeleton()
        pattern = pattern_from_skeleton(skeleton, width=args.width, depth=args.depth, scale=args.length)
    else:
        pattern = random_pattern(args.nodes, seed=args.seed, length=args.length, width=args.width, depth=args.depth)
    if args.noise:
        pattern = add_noise(pattern, amount=args.noise, seed=args.seed)
    if args.smooth is not None:
        pattern = smooth(pattern, args.smooth)
    if args.symmetry > 1:
        pattern = symmetric(pattern, args.symmetry)
    return pattern.timing(speed=args.speed, tau=args.tau)


def run_crack(args):
    out = output_file(args.output, (".png", ".stl", ".vtp", ".ply")) if args.output else None
    size = parse_size(args.size)
    model = substrate(args.on)
    bounds = model.bounds
    anchor = _vector(args.anchor, "--anchor") if args.anchor else (
        (bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, bounds[5])
    pattern = _pattern(args)
    t0 = time.perf_counter()
    crack = carve(model, pattern, anchor, _vector(args.direction, "--direction"), t0=args.t)
    facts = {"on": args.on, **crack.facts(), "seconds": round(time.perf_counter() - t0, 4)}
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.suffix.lower() == ".png":
            render_crack(crack, anchor, out, size)
        else:
            crack.result.save(out)
        facts["output"] = str(out)
    print(json.dumps(facts) if args.json else
          f"{facts['nodes']} nodes, {facts['triangles_object']} -> {facts['triangles_result']} triangles")
    return 0


def render_crack(crack, anchor, path, size):
    import numpy as np

    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=list(size))
    plotter.set_background("white", top="lightsteelblue")
    plotter.add_mesh(crack.result, color=(0.75, 0.72, 0.68))
    centre = crack.points.mean(axis=0)
    span = max(float(np.ptp(crack.points, axis=0).max()), 1e-3)
    outward = centre / max(np.linalg.norm(centre), 1e-9)
    plotter.camera_position = [tuple(centre + outward * span * 2.4 + np.array([0.0, -0.5, 0.4]) * span),
                               tuple(centre), (0.0, 0.0, 1.0)]
    plotter.screenshot(str(path))
    plotter.close()


def register(sub):
    p = sub.add_parser("crack", help="carve a crack (skeleton + profile) into a closed surface; --json, -o PNG/STL")
    p.add_argument("--on", default="stone", help="'stone' (default) or a closed mesh file")
    p.add_argument("--nodes", type=int, default=63, help="nodes of the random pattern (default 63)")
    p.add_argument("--from-plant", metavar="GRAMMAR", help="take the pattern from a plant's branching instead")
    p.add_argument("-n", type=int, default=None, help="with --from-plant: derivation steps")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--length", type=float, default=0.15, help="arc length (or the plant's scale)")
    p.add_argument("--width", type=float, default=0.02, help="profile half-width at the root")
    p.add_argument("--depth", type=float, default=0.04, help="profile depth at the root")
    p.add_argument("--noise", type=float, default=0.0, help="jitter turning angles by +-DEG (with inserted points)")
    p.add_argument("--smooth", type=float, default=None, help="bound the change of turning angles (degrees)")
    p.add_argument("--symmetry", type=int, default=1, help="copies around the root (a circular crack)")
    p.add_argument("--anchor", help="X,Y,Z near the surface (default: top centre of the model)")
    p.add_argument("--direction", default="1,0,0", help="initial direction X,Y,Z (default 1,0,0)")
    p.add_argument("--t", type=float, default=None, help="the crack grown until this time (default: grown)")
    p.add_argument("--speed", type=float, default=1.0, help="growth speed v (t_j = t_i + delta / v)")
    p.add_argument("--tau", type=float, default=0.5, help="growth duration of a node")
    p.add_argument("--json", action="store_true", help="print nodes, triangles before/after, seconds")
    p.add_argument("-o", "--output", help="PNG picture, or the cracked mesh (.stl, .vtp, .ply)")
    p.add_argument("--size", default="800x800", help="image size WIDTHxHEIGHT (default 800x800)")
    p.set_defaults(func=run_crack)
