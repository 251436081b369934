"""``visemeface face``: render the default face (or a user's mesh) to PNG, or export the mesh."""

from __future__ import annotations

from visemeface.commands import _options as opt

ORDER = 10


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "face",
        help="render the embedded face (or your own mesh) to a PNG, or export it as OBJ/PLY/GLB",
        description="Render the embedded procedural face at rest with the headless renderer, and/or "
        "export it as a mesh (format by suffix: .obj .ply .glb .gltf) with its landmarks and regions "
        "in <name>.landmarks.json. --mesh renders a mesh of your own; its landmarks come from "
        "<name>.landmarks.json beside it or --landmarks (vertex indices or [x, y, z] positions, which "
        "are snapped to the nearest vertex).",
        epilog="examples:\n  visemeface face -o face.png --view three-quarter\n"
        "  visemeface face --export face.obj\n"
        "  visemeface face --face ict --identity 7 -o speaker7.png\n"
        "  visemeface face --mesh my_head.ply --landmarks my_head.json -o mine.png --view mouth\n"
        "  visemeface face --prepare scan.obj -o head.obj   (-o is then the head mesh to write)",
        formatter_class=opt.Help,
    )
    p.add_argument("-o", "--output", metavar="PNG", help="PNG image to write (with --prepare: the head mesh)")
    p.add_argument("--export", metavar="MESH", help="write the mesh (.obj/.ply/.glb/.gltf) and its landmarks file")
    from visemeface.render import PROJECTIONS, VIEWS

    p.add_argument("--view", default="face", choices=VIEWS,
                   help="camera preset (default: face)")
    p.add_argument("--size", default="512", metavar="N|WxH",
                   help="image size in pixels, multiples of 16 (default: 512)")
    opt.add_msaa_argument(p)
    p.add_argument("--projection", default="perspective", choices=PROJECTIONS,
                   help="camera projection (default: perspective)")
    p.add_argument("--resolution", type=int, metavar="N",
                   help="approximate vertex count of the embedded face (default: about 4,500)")
    p.add_argument("--rest-gap", type=float, default=0.0, metavar="M",
                   help="opening between the lips at rest in metres (default: 0, closed)")
    opt.add_skin_argument(p)
    p.add_argument("--mesh", metavar="FILE", help="render this mesh instead of the embedded face")
    p.add_argument("--face", metavar="NAME|MESH", help="a built-in face ('ict': the scanned ICT Face Model, "
                   "'procedural': the embedded one) or a mesh, as every animating command's --face")
    p.add_argument("--identity", metavar="SEED|W,...", help="with --face ict: a speaker from ICT's identity "
                   "space, drawn by an integer seed or given as weights of its first modes")
    p.add_argument("--landmarks", metavar="FILE",
                   help="landmarks JSON of --mesh (default: <mesh name>.landmarks.json beside it)")
    p.add_argument("--camera-json", metavar="FILE",
                   help="also write the camera and the rest mouth box in pixels (the analysis sidecar format)")
    p.add_argument("--prepare", metavar="MESH",
                   help="make a head mesh of your own ready to pose: find its landmarks in a frontal render, "
                   "check its units, label its lips, seams and lids, and write it (-o HEAD.obj/.ply/.glb) with "
                   "its landmarks file and a check sheet")
    p.add_argument("--landmark-indices", metavar="FILE",
                   help="with --prepare: the mesh's 68 Multi-PIE landmark vertices (0-based, a JSON list or "
                   "numbers separated by spaces or commas) instead of finding them")
    p.add_argument("--sheet", metavar="PNG",
                   help="with --prepare: the check sheet (landmarks and regions drawn on a render; default "
                   "<HEAD>.check.png beside the output)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def run(args) -> int:
    import json
    from pathlib import Path

    from visemeface.errors import InputError
    from visemeface.face.mesh import load_face, sidecar_path
    from visemeface.outputs import atomic_output, check_new

    if args.prepare:
        return run_prepare(args)
    for name in ("landmark_indices", "sheet"):
        if getattr(args, name):
            raise InputError(f"--{name.replace('_', '-')} needs --prepare")
    if not args.output and not args.export:
        raise InputError("nothing to do: give -o PNG and/or --export MESH")
    if args.mesh and args.face:
        raise InputError("give --face or --mesh, not both")
    if args.face == "procedural" and not (args.identity or args.landmarks):
        args.face = None                        # the embedded face, with its --resolution and --skin
    mesh = args.mesh or args.face
    if mesh and args.resolution is not None:
        raise InputError(f"--resolution applies to the embedded face, not to {mesh}")
    if mesh and args.skin:
        raise InputError(f"--skin colours the embedded face, not {mesh}")
    if args.landmarks and not mesh:
        raise InputError("--landmarks needs --mesh or --face")
    if args.resolution is not None and not 800 <= args.resolution <= 200_000:
        raise InputError(f"--resolution must be a vertex count from 800 to 200000, got {args.resolution}")
    if not 0.0 <= args.rest_gap <= 0.01:
        raise InputError(f"--rest-gap must be from 0 to 0.01 (metres: 0.002 is 2 mm), got {args.rest_gap:g}")
    if args.camera_json and Path(args.camera_json).suffix.lower() != ".json":
        raise InputError("the camera file must be a .json file", args.camera_json)
    if args.identity is not None and not args.face:
        raise InputError("--identity needs --face ict")
    from visemeface.render.renderer import parse_size

    size = parse_size(args.size)
    from visemeface.pipeline import check_msaa

    check_msaa(args.msaa)
    outputs = [Path(p) for p in (args.output, args.camera_json) if p]
    if args.export:
        outputs += [Path(args.export), sidecar_path(args.export)]
    if args.output and Path(args.output).suffix.lower() != ".png":
        raise InputError("the image must be a .png file", args.output)
    if len({p.resolve() for p in outputs}) != len(outputs):
        raise InputError("the outputs must be different files")
    for out in outputs:           # refuse before doing any work; the landmarks file when the face is known
        if not (args.export and out == sidecar_path(args.export)):   # (the same one beside it is kept: save)
            check_new(out, args.force)

    if args.face:
        from visemeface.face import chosen_face

        face = chosen_face(args.face, args.identity, args.landmarks)
    elif args.mesh:
        face = load_face(args.mesh, args.landmarks)
    else:
        from visemeface.face.procedural import default_face
        face = default_face(args.resolution, rest_gap=args.rest_gap, skin=args.skin)

    say = (lambda *a: None) if args.quiet else print
    if args.export:
        mesh_path, side = face.save(args.export, force=args.force)
        say(f"wrote {mesh_path} ({face.n_vertices} vertices, {len(face.quads)} quads, "
              f"{len(face.tris)} triangles) and {side}")
    if args.output or args.camera_json:
        from visemeface.render.renderer import Renderer, save_png
        with Renderer(face, size=size, view=args.view, projection=args.projection, samples=args.msaa) as renderer:
            if args.output:
                save_png(args.output, renderer.render(), force=args.force)
                say(f"wrote {args.output} ({size[0]}x{size[1]}, view {args.view}, {args.projection})")
            if args.camera_json:
                info = renderer.camera_info()
                with atomic_output(args.camera_json, args.force) as tmp:
                    tmp.write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")
                say(f"wrote {args.camera_json}")
    return 0


def run_prepare(args) -> int:
    """``face --prepare MESH -o HEAD``: see :mod:`visemeface.face.prepare`."""
    from pathlib import Path

    from visemeface.errors import InputError
    from visemeface.face.mesh import MESH_SUFFIXES, sidecar_path
    from visemeface.face.prepare import check_sheet, prepare
    from visemeface.outputs import check_new
    from visemeface.render.renderer import save_png

    given = [f"--{n.replace('_', '-')}" for n in ("export", "mesh", "landmarks", "camera_json", "resolution", "skin")
             if getattr(args, n) is not None] + (["--rest-gap"] if args.rest_gap else [])
    if given:
        raise InputError(f"{given[0]} does not go with --prepare (which writes the prepared head to -o)")
    if not args.output:
        raise InputError("--prepare needs -o HEAD (.obj, .ply, .glb or .gltf): where to write the prepared head")
    out = Path(args.output)
    if out.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(f"the prepared head is a mesh: -o must end in {', '.join(MESH_SUFFIXES)}", out)
    sheet = Path(args.sheet) if args.sheet else out.with_name(out.stem + ".check.png")
    if sheet.suffix.lower() != ".png":
        raise InputError("the check sheet must be a .png file", sheet)
    outputs = [out, sidecar_path(out), sheet]
    if len({p.resolve() for p in outputs + [Path(args.prepare)]}) != 4:
        raise InputError("the input, the head, its landmarks file and the check sheet must be different files")
    for p in outputs:
        check_new(p, args.force)
    say = (lambda *a: None) if args.quiet else print
    face, lm68 = prepare(args.prepare, args.landmark_indices, say)
    image = check_sheet(face, lm68)
    mesh_path, side = face.save(out, force=args.force)
    save_png(sheet, image, force=args.force)
    say(f"wrote {mesh_path} ({face.n_vertices} vertices, metres), {side} and the check sheet {sheet}")
    return 0
