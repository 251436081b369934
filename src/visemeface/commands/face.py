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
        epilog="examples: visemeface face -o face.png --view three-quarter | "
        "visemeface face --export face.obj | "
        "visemeface face --mesh my_head.ply --landmarks my_head.json -o mine.png --view mouth",
    )
    p.add_argument("-o", "--output", metavar="PNG", help="PNG image to write")
    p.add_argument("--export", metavar="MESH", help="write the mesh (.obj/.ply/.glb/.gltf) and its landmarks file")
    from visemeface.render import PROJECTIONS, VIEWS

    p.add_argument("--view", default="face", choices=VIEWS,
                   help="camera preset (default: face)")
    p.add_argument("--size", default="512", metavar="N|WxH",
                   help="image size in pixels, multiples of 16 (default: 512)")
    p.add_argument("--projection", default="perspective", choices=PROJECTIONS,
                   help="camera projection (default: perspective)")
    p.add_argument("--resolution", type=int, metavar="N",
                   help="approximate vertex count of the embedded face (default: about 4,500)")
    p.add_argument("--rest-gap", type=float, default=0.0, metavar="M",
                   help="opening between the lips at rest in metres (default: 0, closed)")
    p.add_argument("--mesh", metavar="FILE", help="render this mesh instead of the embedded face")
    p.add_argument("--landmarks", metavar="FILE",
                   help="landmarks JSON of --mesh (default: <mesh name>.landmarks.json beside it)")
    p.add_argument("--camera-json", metavar="FILE",
                   help="also write the camera and the rest mouth box in pixels (the analysis sidecar format)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    opt.add_quiet(p)
    p.set_defaults(func=run)


def run(args) -> int:
    import json
    from pathlib import Path

    from visemeface.errors import InputError
    from visemeface.face.mesh import load_face, sidecar_path
    from visemeface.outputs import atomic_output, check_new

    if not args.output and not args.export:
        raise InputError("nothing to do: give -o PNG and/or --export MESH")
    if args.mesh and args.resolution is not None:
        raise InputError("--resolution applies to the embedded face, not to --mesh")
    if args.landmarks and not args.mesh:
        raise InputError("--landmarks needs --mesh")
    from visemeface.render.renderer import parse_size

    size = parse_size(args.size)
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

    if args.mesh:
        face = load_face(args.mesh, args.landmarks)
    else:
        from visemeface.face.procedural import default_face
        face = default_face(args.resolution, rest_gap=args.rest_gap)

    say = (lambda *a: None) if args.quiet else print
    if args.export:
        mesh_path, side = face.save(args.export, force=args.force)
        say(f"wrote {mesh_path} ({face.n_vertices} vertices, {len(face.quads)} quads, "
              f"{len(face.tris)} triangles) and {side}")
    if args.output or args.camera_json:
        from visemeface.render.renderer import Renderer, save_png
        with Renderer(face, size=size, view=args.view, projection=args.projection) as renderer:
            if args.output:
                save_png(args.output, renderer.render(), force=args.force)
                say(f"wrote {args.output} ({size[0]}x{size[1]}, view {args.view}, {args.projection})")
            if args.camera_json:
                info = renderer.camera_info()
                with atomic_output(args.camera_json, args.force) as tmp:
                    tmp.write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")
                say(f"wrote {args.camera_json}")
    return 0
