"""``eos plan``: one grasp plan on a scene, with a live trace of the cycles (options: README,
"Planning", and ``eos plan --help``)."""

from __future__ import annotations

import argparse
import sqlite3
from typing import IO, Any, NoReturn

from eos_svc.cli import view as view_options
from eos_svc.cli.common import add_weight_arguments, fail, finite_float, positive_float
from eos_svc.cli.hands import add_hand_argument, chosen_hand
from eos_svc.drivers.worlds import WORLDS
from eos_svc.errors import ValidationError
from eos_svc.records import REPEAT_SKIP, CycleRecord

#: request field -> command-line option, for error messages
FIELD_OPTIONS = {
    "object.shape": "--shape",
    "object.radius": "--radius",
    "object.radii": "--radii",
    "object.length": "--length",
    "object.size": "--size",
    "object.position": "--position",
    "object.rpy": "--rpy",
    "weights": "--w-default/--w-opportunistic/--w-learned",
    "seed": "--seed",
    "tactile_noise": "--noise",
    "max_cycles": "--max-cycles",
    "deadline_s": "--deadline",
    "agents": "--agent",
    "friction": "--friction",
    "encoder_noise": "--encoder-noise",
    "link_error": "--link-error",
}


def add_object_arguments(parser: argparse.ArgumentParser) -> None:
    """Options choosing the object (shared with other commands)."""
    g = parser.add_argument_group("object (SI units: m, rad)")
    g.add_argument(
        "--shape", default="sphere", help="sphere, ellipsoid, cylinder, box, capsule or mesh (sphere)"
    )
    g.add_argument("--file", help="mesh: an OBJ, STL or PLY file")
    g.add_argument("--scale", type=positive_float, help="mesh: the file's units in metres (1)")
    g.add_argument(
        "--table", type=finite_float, metavar="Z", help="a table under the object, its top at height Z (m)"
    )
    g.add_argument("--radius", type=positive_float, help="sphere/cylinder/capsule radius (0.03 for a sphere)")
    g.add_argument(
        "--radii", type=positive_float, nargs=3, metavar=("A", "B", "C"), help="ellipsoid semi-axes"
    )
    g.add_argument("--length", type=positive_float, help="cylinder/capsule length")
    g.add_argument("--size", type=positive_float, nargs=3, metavar=("X", "Y", "Z"), help="box edge lengths")
    g.add_argument("--position", type=finite_float, nargs=3, metavar=("X", "Y", "Z"), help="object centre")
    g.add_argument("--rpy", type=finite_float, nargs=3, metavar=("R", "P", "Y"), help="object orientation")


def add_request_arguments(
    parser: argparse.ArgumentParser, friction_default: float | None = 0.5
) -> argparse._ArgumentGroup:
    """The options that make a plan request (shared by ``eos plan`` and ``eos client plan``):
    the groups object, weights and run; returns the run group for more options."""
    add_object_arguments(parser)
    add_weight_arguments(parser)
    g = parser.add_argument_group("run")
    g.add_argument("--seed", type=int, default=1, help="seed of the search and the tactile noise (1)")
    g.add_argument("--noise", type=finite_float, default=2e-4, help="tactile noise std, m (2e-4)")
    g.add_argument("--encoder-noise", type=finite_float, default=0.0, help="joint-encoder noise std, rad (0)")
    g.add_argument("--link-error", type=finite_float, default=0.0, help="link-length error std, m (0)")
    g.add_argument("--max-cycles", type=int, default=2000, help="cycle limit (2000)")
    g.add_argument("--deadline", type=positive_float, help="wall-clock budget, s (10; --world drake 600)")
    g.add_argument(
        "--friction",
        type=finite_float,
        default=friction_default,
        metavar="MU",
        help="Coulomb friction μ at the fingertips, for the grasp quality "
        + ("(the request's default when omitted)" if friction_default is None else f"({friction_default})"),
    )
    g.add_argument(
        "--agent",
        action="append",
        default=None,
        metavar="NAME",
        help="add a plug-in agent, repeatable: an eos_svc.agents entry point or module:attr "
        "(a service: one it offers)",
    )
    return g


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = add_request_arguments(parser)
    add_hand_argument(g)
    g.add_argument(
        "--world",
        choices=WORLDS,
        default="kinematic",
        help="kinematic (the object fixed; default) or drake (a free body on a table; needs the lift test)",
    )
    g.add_argument(
        "--memory",
        metavar="DB",
        help="grasp memory (SQLite file): adds the recall agent (give it a --w-learned) and records the plan",
    )
    g.add_argument(
        "--check-board",
        action="store_true",
        help="every agent held to the board entries it declares and their types (a breach: status error)",
    )
    out = parser.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print the result as JSON instead of the trace")
    out.add_argument(
        "--record",
        metavar="FILE",
        help="write the request, every cycle record and the result as JSON lines (eos replay)",
    )
    out.add_argument("--picture", metavar="PNG", help="draw the final grasp to PNG")
    out.add_argument("--quiet", action="store_true", help="no live trace, only the result")
    view_options.add_html_argument(out)  # --html (3-D page of the plan)
    view_options.add_view_arguments(out)  # --view, --view-port, --view-wait, --view-hold
    out.add_argument(
        "--validate",
        action="store_true",
        help="simulate the final grasp in Drake (with the plan's hand) and add the verdict to the result; "
        "the exit status still follows the plan",
    )


def validated(result: Any, args: argparse.Namespace, hand: Any = None) -> Any:
    """The result with its Drake validation (of the plan's ``hand``; ``None``: the default hand)
    when ``--validate`` was given (exit 2 on a bad case)."""
    if not getattr(args, "validate", False):
        return result
    from eos_svc.cli.validate import validate_or_fail

    return result.with_validation(validate_or_fail(result, hand=hand))


def request_dict(args: argparse.Namespace) -> dict[str, Any]:
    """The JSON request the options describe."""
    obj: dict[str, Any] = {"shape": args.shape}
    if args.shape == "sphere" and args.radius is None:
        obj["radius"] = 0.03
    for name in ("radius", "radii", "length", "size", "file", "scale", "position", "rpy"):
        value = getattr(args, name)
        if value is not None:
            obj[name] = value
    return {
        "object": obj,
        "weights": {
            "default": args.w_default,
            "opportunistic": args.w_opportunistic,
            "learned": args.w_learned,
        },
        "seed": args.seed,
        "tactile_noise": args.noise,
        "max_cycles": args.max_cycles,
        # 10 s; 600 s in the Drake world
        "deadline_s": args.deadline or (600.0 if getattr(args, "world", "kinematic") == "drake" else 10.0),
        "friction": args.friction,
        **({"world": args.world} if getattr(args, "world", "kinematic") != "kinematic" else {}),
        **({"agents": list(args.agent)} if getattr(args, "agent", None) else {}),
        **({"encoder_noise": args.encoder_noise} if args.encoder_noise else {}),
        **({"link_error": args.link_error} if args.link_error else {}),
        **({} if args.table is None else {"table": {"height": args.table}}),
    }


def format_world(world: dict) -> str:
    """The Drake world's figures in one line."""
    lift = world.get("lift") or {}
    held = "held" if lift.get("held") else f"not held ({lift.get('why', 'no lift test')})"
    moved = ""
    if world.get("moved_past_relocation_limit"):
        moved = " (past 2 mm: the plan's reason says whether it was re-located)"
    return (
        f"drake world: object moved {world['object_moved_mm']:.1f} mm{moved}; lift test: {held}; "
        f"{world['simulated_s']:.1f} s simulated, real-time factor {world['real_time_factor']}"
    )


def format_cycle(record: CycleRecord) -> str:
    """Two readable lines per cycle: stage and every total (``·`` = not eligible, ``@remote`` =
    a remote agent), a line per agent skipped as unavailable, then the chosen agent, its
    outcome and what it did."""
    ratings = " ".join(
        f"{r.name}{'' if r.where == 'local' else '@' + r.where}={r.total:.2f}{'' if r.eligible else '·'}"
        for r in record.ratings
    )
    chosen = record.chosen or "-"
    outcome = f" [{record.outcome.value}]" if record.outcome is not None else ""
    skips = "".join(
        f"\n     {r.name} skipped: {r.skipped}"
        for r in record.ratings
        if r.skipped and r.skipped != REPEAT_SKIP
    )
    return f"{record.seq:4d} {record.stage:<11} {ratings}{skips}\n     -> {chosen}{outcome}: {record.detail}"


def _postulate_lines(shape: dict[str, Any]) -> list[str]:
    """The postulated object (request form) and the competing classes, when post_shape gave them."""
    obj = shape.get("object")
    if obj is None:
        return []
    sizes = {k: v for k, v in obj.items() if k not in ("shape", "position", "rpy")}
    if obj.get("shape") == "mesh":  # the convex hull of the touches: its size in vertices and faces
        fmt = f"{len(obj.get('vertices', []))} vertices, {len(obj.get('faces', []))} faces"
    else:
        fmt = ", ".join(
            f"{k} {[round(x * 1000, 1) for x in v] if isinstance(v, list) else round(v * 1000, 1)} mm"
            for k, v in sizes.items()
        )
    pos = [round(x * 1000, 1) for x in obj["position"]]
    pose = (
        "rpy " + str([round(x, 3) + 0.0 for x in obj["rpy"]])
        if shape.get("pose_known")
        else "pose assumed upright"
    )
    out = [f"postulate: {obj['shape']} {fmt} at {pos} mm, {pose}"]
    classes = (shape.get("evidence") or {}).get("classes")
    if classes:
        out.append("classes: " + ", ".join(f"{k} {v:.0%}" for k, v in classes.items()))
    return out


def format_result(result: Any) -> str:
    """A short human summary of a :class:`~eos_svc.agents.PlanResult`."""
    lines = [
        f"status: {result.status} — {result.reason}",
        f"cycles: {result.cycles} {result.cycles_per_stage}; stages completed: "
        f"{', '.join(result.stages_completed) or 'none'}",
    ]
    if result.shape:
        s = result.shape
        half = s["grasp_radius"]
        size = "size unknown" if half is None else f"half-height {half * 1000:.2f} mm"
        confidence = s["confidence"]
        lines.append(
            f"shape: {s['class']}, {size}, confidence {confidence:.0%} (EP1 runs: {result.ep1_runs}; "
            f"{result.touches} touches, {result.probes} probes)"
        )
        lines.extend(_postulate_lines(s))
    truth = result.ground_truth
    diameter_mm = truth["diameter"] * 1000
    lines.append(f"truth: {truth['shape']}, diameter {diameter_mm:.1f} mm, d/h {truth['d_over_h']:.2f}")
    touching = ", ".join(f for f, c in result.contacts.items() if c["touching"]) or "none"
    lines.append(f"contacts: {touching}; good grasp: {'yes' if result.good_grasp else 'no'}")
    if getattr(result, "friction", None) is not None:
        closure = "force closure" if getattr(result, "force_closure", False) else "no force closure"
        eps = result.epsilon
        lines.append(f"quality: {closure} at μ = {result.friction:g}, ε = {eps:.3f} (Ferrari-Canny)")
    world = getattr(result, "world", None)  # a replayed recording's result may have none
    if world is not None:
        lines.append(format_world(world))
    lines.append(f"seed {result.seed}, weights {result.weights}, {result.wall_time_s * 1000:.1f} ms")
    if getattr(result, "validation", None):
        from eos_svc.cli.validate import format_validation

        lines.append(format_validation(result.validation))
    return "\n".join(lines)


def fail_field(exc: ValidationError) -> NoReturn:
    """Exit 2 naming the command-line option of the request field ``exc`` names."""
    fail(f"{FIELD_OPTIONS.get(exc.field.split('[')[0], exc.field)}: {exc.reason}")


def run(args: argparse.Namespace) -> int:
    from eos_svc.agents import PlanRequest, plan  # heavy imports only when planning
    from eos_svc.recording import cycle_line, header_line, result_line
    from eos_svc.world.admission import check_plannable

    try:
        request = PlanRequest.from_dict(request_dict(args))
    except ValidationError as exc:
        fail_field(exc)
    hand = chosen_hand(args)
    try:
        check_plannable(request, hand)  # out of reach, overlapping the hand, wider than its span
    except ValidationError as exc:
        fail_field(exc)
    record_file: IO[str] | None = None
    if args.record:
        try:
            record_file = open(args.record, "w", encoding="utf-8")  # noqa: SIM115 - closed below
        except OSError as exc:
            fail(f"--record: cannot write {args.record!r}: {exc.strerror}")
        record_file.write(header_line(request, getattr(args, "hand", "hand3x3")) + "\n")

    def on_cycle(record: CycleRecord) -> None:
        if record_file is not None:
            record_file.write(cycle_line(record) + "\n")
        if not args.json and not args.quiet:
            print(format_cycle(record), flush=True)
        if view is not None:
            view.cycle(record)

    memory = None
    if getattr(args, "memory", None):
        from eos_svc.agents.memory import GraspMemory

        try:
            memory = GraspMemory(args.memory)
        except (OSError, sqlite3.Error) as exc:
            fail(f"--memory: cannot open {args.memory!r}: {exc}")
    view = view_options.open_view(args, hand)  # --view: a live page following the cycles
    if view is not None:
        view.start(request)
        view_options.wait_for_browser(view, args.view_wait)
    try:
        result = plan(
            request,
            on_cycle=on_cycle,
            hand=hand,
            memory=memory,
            check_board=getattr(args, "check_board", False),
            check=False,  # check_plannable has just run on this request and hand
        )
        if record_file is not None:
            record_file.write(result_line(result) + "\n")
    except ValidationError as exc:
        fail_field(exc)
    finally:
        if record_file is not None:
            record_file.close()
    if args.picture:
        from eos_svc.view.picture import draw_result

        if result.q_final is None:
            fail("--picture: no final hand configuration (the end agent never judged the grasp)", code=1)
        try:
            draw_result(result, args.picture, hand=hand)
        except OSError as exc:
            fail(f"--picture: cannot write {args.picture!r}: {exc.strerror}")
    result = validated(result, args, hand)
    if getattr(args, "html", None):  # --html FILE
        records = [r.to_dict() for r in result.trace]
        view_options.write_html(args.html, request, records, result.to_dict(), hand)
    if args.json:
        print(result.to_json())
    else:
        print(format_result(result))
    if view is not None:  # --view: the final grasp and the whole plan as the page's animation
        view.finish(result.to_dict())
        view_options.hold_view(view, args.view_hold)
    return plan_exit_code(result.status)


def plan_exit_code(status: str) -> int:
    """0 for ``success`` (the end agent judged the grasp good), 1 for any other status."""
    return 0 if status == "success" else 1
