"""The ``ndtrace`` command: render an N-dimensional scene to a picture.

    ndtrace scenes/tesseract.toml -o tesseract.png
    ndtrace scenes/tesseract.toml -o tesseract.exr --retina retina.exr --samples 4
    ndtrace scenes/penteract.toml -o penteract.png --composite mip --view 40,25 --size 800x600
    ndtrace my_scene.py -o out.png          # a Python script defining scene() -> ndtrace.Scene
    ndtrace scenes/tesseract_spin.toml -o spin.gif --frames 24   # the scene's [animation]
    ndtrace scenes/cube.toml -o cube.jpg --set camera.fov=40 --set objects.0.material.color=[1,0,0]
    python -m ndtrace scenes/cube.toml -o cube.png --transparent   # the same command
    ndtrace view scenes/tesseract.toml      # the interactive viewer (see ndtrace view --help)

The whole scene is validated before any work; errors are one line on stderr (exit status 2),
with a traceback only under --debug. Ctrl-C stops within a second, leaves no partial output
and exits with status 130.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time
import traceback

from . import _ndtrace
from ._command import (
    THREADS_PER_CORE as THREADS_PER_CORE,
    ScriptError as ScriptError,
    UsageError,
    apply_sets,
    capped_threads,
    ints,
    load_scene,
    max_threads as max_threads,
)
from ._description import plain
from ._ndtrace import __version__
from ._optional import install
from .animation import animate, write_frames
from .cluster import check_address, connect, distributed_module
from .composite import COLOR_BY, EDGE_COLOR_BY, PALETTES, scene_options
from .files import IMAGE_FORMATS, write_exr, write_image
from .retina import trace
from .scene import Scene, load_dict
from .slicing import picture as slice_picture, slice_options, sliced
from .svg import write_svg
from .viewer.cli import main as view

MODES: tuple[str, ...] = tuple(_ndtrace.RENDER_MODES)  # render.mode, as the core names them
COMPOSITES: tuple[str, ...] = tuple(_ndtrace.COMPOSITE_MODES)  # composite.mode
LAYOUTS = ("single", "sections", "stereo", "slice")  # composite.layout
#: Axis names of --slice AXIS=OFFSET (also x0 … x7).
AXES = ("x", "y", "z", "w")
#: Frames per second of a turntable video.
TURNTABLE_FPS = 12.0


def _terminate(signum, _frame):
    """SIGTERM and SIGHUP stop the work as Ctrl-C does (partial outputs removed)."""
    raise KeyboardInterrupt(signal.Signals(signum).name)


class Progress:
    """A one-line progress bar with an ETA on stderr."""

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.stage = ""
        self.start = time.monotonic()
        self.last = 0.0
        self.tty = sys.stderr.isatty()

    def begin(self, stage: str) -> None:
        self.stage = stage
        self.start = time.monotonic()
        self.last = 0.0
        self.update(0, 1)

    def update(self, done: int, total: int) -> None:
        if self.quiet:
            return
        now = time.monotonic()
        if done < total and now - self.last < (0.1 if self.tty else 2.0):
            return
        self.last = now
        frac = done / total if total else 1.0
        elapsed = now - self.start
        eta = f"ETA {elapsed / frac - elapsed:5.1f} s" if 0 < frac < 1 else f"{elapsed:5.1f} s"
        bar = "#" * int(frac * 30)
        line = f"{self.stage:<12} [{bar:<30}] {frac * 100:5.1f}%  {eta}"
        sys.stderr.write(("\r" + line) if self.tty else (line + "\n"))
        sys.stderr.flush()

    def end(self) -> None:
        if not self.quiet and self.tty:
            sys.stderr.write("\n")
            sys.stderr.flush()


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="ndtrace",
        description="Render an N-dimensional scene (N = 2…8) to a picture: trace the N-D camera's "
        "(N−1)-D retina, then composite it to 2D.",
        epilog=__doc__.split("\n\n")[1] if __doc__ else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", help="a .toml scene, or a .py script defining scene() -> ndtrace.Scene")
    p.add_argument("-o", "--output", required=True,
                   help="the picture to write: .png, .jpg, .webp, .tif, .exr or .svg (the feature "
                   "edges with exact N-D visibility, as vector paths); for an animation "
                   ".gif or .mp4 (the video), or .png (numbered frames out_0001.png … plus a video)")
    p.add_argument("--retina", metavar="FILE.exr", help="also write the traced retina there")
    p.add_argument("--resolution", help="cells per retina axis: R or R1,R2,… (overrides the camera's)")
    p.add_argument("--samples", type=int, help="rays per retina cell")
    p.add_argument("--seed", type=int, help="seed of the sample jitter")
    p.add_argument("--threads", type=int, help="worker threads (default: every core)")
    p.add_argument("--mode", choices=MODES, help="what the tracer shows (render.mode)")
    p.add_argument("--composite", choices=COMPOSITES, help="how the retina becomes a picture")
    p.add_argument("--view", metavar="AZIMUTH,ELEVATION", help="compositing camera angles, degrees")
    p.add_argument("--size", metavar="WxH", help="picture size in pixels")
    p.add_argument("--layout", choices=LAYOUTS,
                   help="for N ≥ 4: one view, the view with three orthogonal sections, or a stereo pair")
    p.add_argument("--section", metavar="X,Y,Z",
                   help="the point the sections pass through (volume coordinates, [-1, 1])")
    p.add_argument("--stereo-angle", type=float, metavar="DEGREES", help="between the stereo pair's eyes")
    p.add_argument("--cutaway", metavar="SPEC",
                   help="remove part of the volume: half_space:NX,NY,NZ[,OFFSET], "
                   "sphere:CX,CY,CZ,R or box:X0,Y0,Z0,X1,Y1,Z1 (volume coordinates)")
    p.add_argument("--turntable", type=int, metavar="F",
                   help="with -o .gif/.mp4 (or .png: numbered frames): F frames of the compositing "
                   "camera orbiting one traced retina")
    p.add_argument("--title", metavar="TEXT", help="a caption line above the picture (composite.title)")
    p.add_argument("--legend", choices=("auto", "true", "false"),
                   help="the colour bar and keys along the bottom: when the scene has a colormap, "
                   "color_by or labels (auto, the default), always or never")
    p.add_argument("--axes", choices=("auto", "true", "false"),
                   help="the N-D axes glyph in the view's lower-left corner (auto: for N ≥ 4)")
    p.add_argument("--edge-color-by", choices=EDGE_COLOR_BY,
                   help="the feature edges: by N-D depth (the default), by direction, or one colour")
    p.add_argument("--color-by", choices=COLOR_BY,
                   help="every object's material.color_by: a palette colour per cell, per object, "
                   "or the N-D depth through a colormap")
    p.add_argument("--palette", choices=PALETTES, help="every object's material.palette (default tab10)")
    p.add_argument("--slice", metavar="AXIS=OFFSET|NORMAL:OFFSET",
                   help="render the (N−1)-D slice by a hyperplane: w=0.3 (an axis: x, y, z, w or "
                        "x0 … x7) or 1,0,0,1:0.5 (normal and offset); sets [slice]")
    p.add_argument("--frames", type=int, metavar="K",
                   help="render K frames of the scene's [animation] (implied by -o .gif/.mp4)")
    p.add_argument("--video", choices=("gif", "mp4", "none"), default="gif",
                   help="with --frames and -o .png: the video written beside the frames")
    _add_output_options(p)
    p.add_argument("--dask", nargs="?", const="local", type=_dask_address, metavar="ADDRESS",
                   help="trace (or render an animation's frames) on Dask: 'local' (the default: "
                        "a LocalCluster on this machine) or a scheduler tcp://HOST:PORT "
                        f"({install('dask')})")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.add_argument("--version", action="version", version=f"ndtrace {__version__}")
    return p


def _dask_address(text: str) -> str:
    try:
        return check_address(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(
            f"{e} (give --dask after the scene, or write --dask local)") from None


def _add_output_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a scene key, e.g. camera.fov=40 or objects.0.material.color=[1,0,0] "
                   "(VALUE in TOML syntax; a bare word is a string); repeatable, applied in order "
                   "before the other options")
    p.add_argument("--transparent", action="store_true",
                   help="keep alpha: the picture without the scene's background (.png, .webp, "
                   ".tif, .exr); by default pictures are opaque over the background")
    p.add_argument("--keep-frames", action="store_true",
                   help="with -o .gif/.mp4: also write the numbered PNG frames")


def _picture_options(scene: Scene, transparent: bool) -> dict:
    """The composite options of a still: the scene's, without its background when transparent
    (then the picture is premultiplied RGBA over black, as transparent files store it)."""
    options = scene_options(scene.to_dict())
    if transparent:
        options["background"] = None
    return options


def _write_picture(path: str, picture, transparent: bool) -> None:
    if path.lower().endswith(".exr"):
        write_exr(path, picture)
    else:
        write_image(path, picture, transparent=transparent)


def _floats(text: str, option: str, count: int | tuple[int, ...]) -> list[float]:
    counts = (count,) if isinstance(count, int) else count
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise UsageError(f"{option}: expected numbers separated by ',', got {text!r}") from None
    if len(values) not in counts:
        raise UsageError(f"{option}: expected {' or '.join(map(str, counts))} numbers, got {text!r}")
    return values


def _cutaway(text: str) -> dict:
    """``--cutaway`` SPEC → the ``composite.cutaway`` table."""
    shape, _, numbers = text.partition(":")
    if shape == "half_space":
        v = _floats(numbers, "--cutaway half_space", (3, 4))
        return {"shape": shape, "normal": v[:3], "offset": v[3] if len(v) == 4 else 0.0}
    if shape == "sphere":
        v = _floats(numbers, "--cutaway sphere", 4)
        return {"shape": shape, "center": v[:3], "radius": v[3]}
    if shape == "box":
        v = _floats(numbers, "--cutaway box", 6)
        return {"shape": shape, "min": v[:3], "max": v[3:]}
    raise UsageError(f"--cutaway: expected half_space:…, sphere:… or box:…, got {text!r}")


def _composite_flags(args: argparse.Namespace) -> dict:
    """The ``[composite]`` keys the flags set. The core checks each flag's keys as it checks a
    scene's table, so an error names the flag and the key: ``--size: composite.size: …``."""
    flags: list[tuple[str, dict]] = []
    if args.composite:
        flags.append(("--composite", {"mode": args.composite}))
    if args.view:
        try:
            az, el = (float(v) for v in args.view.split(","))
        except ValueError:
            raise UsageError(f"--view: expected AZIMUTH,ELEVATION in degrees, got {args.view!r}") from None
        flags.append(("--view", {"azimuth": az, "elevation": el}))
    if args.size:
        size = ints(args.size.lower(), "--size", "x", positive=False)
        if len(size) != 2:
            raise UsageError(f"--size: expected WxH, got {args.size!r}")
        flags.append(("--size", {"size": size}))
    if args.layout:
        flags.append(("--layout", {"layout": args.layout}))
    if args.section:
        flags.append(("--section", {"section": _floats(args.section, "--section", 3)}))
    if args.stereo_angle is not None:
        flags.append(("--stereo-angle", {"stereo_angle": args.stereo_angle}))
    if args.cutaway:
        flags.append(("--cutaway", {"cutaway": _cutaway(args.cutaway)}))
    if args.turntable is not None:
        flags.append(("--turntable", {"turntable": args.turntable}))
    if args.title is not None:
        flags.append(("--title", {"title": args.title}))
    toggle = {"auto": "auto", "true": True, "false": False}
    if args.legend is not None:
        flags.append(("--legend", {"legend": toggle[args.legend]}))
    if args.axes is not None:
        flags.append(("--axes", {"axes": toggle[args.axes]}))
    if args.edge_color_by is not None:
        flags.append(("--edge-color-by", {"edge_color_by": args.edge_color_by}))
    keys: dict = {}
    for flag, values in flags:
        _ndtrace.check_composite(values, flag)
        keys.update(values)
    return keys


def slice_flag(text: str, dim: int) -> dict:
    """The ``[slice]`` table of ``--slice``: ``AXIS=OFFSET`` (x, y, z, w or x0 … x7) or
    ``NORMAL:OFFSET`` (N comma-separated numbers, then the offset)."""
    def number(word: str) -> float:
        try:
            x = float(word)
        except ValueError:
            raise UsageError(f"--slice {text}: {word!r} is not a number") from None
        if not math.isfinite(x):
            raise UsageError(f"--slice {text}: {word!r} is not finite")
        return x

    if "=" in text:
        axis, _, value = text.partition("=")
        axis = axis.strip().lower()
        names = {name: k for k, name in enumerate(AXES)} | {f"x{k}": k for k in range(8)}
        if axis not in names or names[axis] >= dim:
            valid = ", ".join(list(AXES[:dim]) + [f"x0 … x{dim - 1}"])
            raise UsageError(f"--slice {text}: unknown axis {axis!r} for dim = {dim} "
                             f"(expected {valid})")
        normal = [0.0] * dim
        normal[names[axis]] = 1.0
        return {"normal": normal, "offset": number(value)}
    if ":" in text:
        vector, _, value = text.rpartition(":")
        normal = [number(w) for w in vector.split(",")]
        if len(normal) != dim:
            raise UsageError(f"--slice {text}: expected {dim} numbers before ':' (dim = {dim}), "
                             f"got {len(normal)}")
        if not any(normal):
            raise UsageError(f"--slice {text}: the normal must not be zero")
        return {"normal": normal, "offset": number(value)}
    raise UsageError(f"--slice {text}: expected AXIS=OFFSET (e.g. w=0.3) or NORMAL:OFFSET "
                     "(e.g. 1,0,0,1:0.5)")


def _check_output(path: str, exts: tuple[str, ...], option: str) -> None:
    if not path.lower().endswith(exts):
        raise UsageError(f"{option} {path}: unknown extension: expected {' or '.join(exts)}")
    if os.path.isdir(path):
        raise UsageError(f"{option} {path}: is a folder, not a file to write")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise UsageError(f"{option} {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise UsageError(f"{option} {path}: folder {folder} is not writable")


def run(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    # 1. Validate everything before any work or progress output.
    video_out = args.output.lower().endswith((".gif", ".mp4"))
    if args.turntable is not None:
        if args.frames is not None:
            raise UsageError("--turntable: orbits one traced retina; it does not combine with --frames")
        if not args.output.lower().endswith((".gif", ".mp4", ".png")):
            raise UsageError(f"--turntable: writes a .gif or .mp4 (or numbered .png frames), not {args.output}")
    animating = (args.frames is not None or video_out) and args.turntable is None
    stills = tuple(IMAGE_FORMATS) + (".exr", ".svg")
    _check_output(args.output, (".png", ".gif", ".mp4") if animating or args.turntable is not None
                  else stills, "-o")
    if args.transparent and (animating or args.output.lower().endswith((".jpg", ".jpeg"))):
        raise UsageError("--transparent: GIF, MP4 and JPEG pictures are opaque; write a .png, "
                         ".webp, .tif or .exr still")
    if args.frames is not None and args.frames < 1:
        raise UsageError(f"--frames: must be at least 1, got {args.frames}")
    if animating and args.retina:
        raise UsageError("--retina: a retina is written for a still, not for an animation")
    if args.retina:
        _check_output(args.retina, (".exr",), "--retina")
        if os.path.realpath(args.retina) == os.path.realpath(args.output):
            raise UsageError(f"--retina {args.retina}: the same file as -o {args.output}; "
                             "give the two outputs different names")
    if os.path.realpath(args.scene) in (os.path.realpath(args.output),
                                         os.path.realpath(args.retina or args.output)):
        raise UsageError(f"{args.scene}: an output would overwrite the scene file")
    args.threads = capped_threads(args.threads, "ndtrace", args.quiet)
    for name in ("samples", "seed", "frames"):
        value = getattr(args, name)
        if value is not None and not 0 <= value < 2**32:
            raise UsageError(f"--{name}: must be in 0..{2**32 - 1}, got {value}")
    scene = load_scene(args.scene)
    scene = apply_sets(scene, args.set, scene._base or os.path.dirname(os.path.abspath(args.scene)))
    data = scene.to_dict()
    render = data.setdefault("render", {})
    if args.resolution:
        res = ints(args.resolution, "--resolution")
        data["camera"]["resolution"] = res[0] if len(res) == 1 else res
    if args.samples is not None:
        render["samples"] = args.samples
    if args.seed is not None:
        render["seed"] = args.seed
    if args.mode:
        render["mode"] = args.mode
    for key, value in (("color_by", args.color_by), ("palette", args.palette)):
        if value is not None:
            for o in data.get("objects") or []:
                o["material"] = {**(o.get("material") or {}), key: value}
    if args.slice is not None:
        data["slice"] = slice_flag(args.slice, int(data["dim"]))
    comp = {**(data.get("composite") or {}), **_composite_flags(args)}
    if comp:
        data["composite"] = comp
    scene = load_dict(data, base=scene._base or os.path.dirname(os.path.abspath(args.scene)))
    turntable = int(comp.get("turntable") or 0)
    if animating and turntable and args.frames is None:
        animating = False  # the scene's [composite] asks for a turntable
    if turntable and not args.output.lower().endswith((".gif", ".mp4", ".png")):
        raise UsageError(f"composite.turntable: writes a .gif or .mp4 (or numbered .png frames), "
                         f"not {args.output}")

    if animating and scene.to_dict().get("animation") is None:
        raise UsageError(f"{args.scene}: the scene has no [animation] table to render frames of")
    # The picture (or a turntable's frames) checked by the memory guard before anything is
    # traced: a refusal names --size or --turntable's key and the limit.
    picture = {k: v for k, v in _picture_options(scene, args.transparent).items() if k != "background"}
    if not animating:
        _ndtrace.check_picture_memory(list(scene.retina_shape), plain(picture))
    else:
        _ndtrace.check_picture_memory(list(scene.retina_shape), plain(dict(picture, turntable=0)))
    if args.dask:
        try:
            distributed_module()
        except ImportError as e:
            raise UsageError(f"--dask: {e}") from None

        with connect(args.dask) as client:
            return _render(args, scene, animating, turntable, client)
    return _render(args, scene, animating, turntable, None)


def _render(args: argparse.Namespace, scene: Scene, animating: bool, turntable: int, client) -> int:
    """Steps 2 and 3 of :func:`run`: trace (on ``client``'s Dask workers if given) and
    composite with a progress bar, then write each file atomically."""
    bar = Progress(args.quiet)
    if animating:
        video = None if args.video == "none" else args.video
        bar.begin("frames")
        paths = animate(scene, args.output, frames=args.frames, video=video,
                        threads=args.threads, progress=bar.update, keep_frames=args.keep_frames,
                        client=client)
        bar.end()
        if not args.quiet:
            pngs = [p for p in paths if p.endswith(".png")]
            videos = [p for p in paths if not p.endswith(".png")]
            written = ([f"{len(pngs)} frames {pngs[0]} … {pngs[-1]}"] if pngs else []) + videos
            print("wrote " + " and ".join(written), file=sys.stderr)
        return 0
    options = _picture_options(scene, args.transparent)
    if (cut := sliced(scene, options.get("size"))) is not scene:
        # The (N−1)-D slice is the scene to trace (the CLI's [slice], layout not "slice").
        options = slice_options(options, cut.dim)
        scene = cut
    bar.begin("tracing")
    retina = trace(scene, threads=args.threads, progress=bar.update, client=client)
    bar.end()
    if args.output.lower().endswith(".svg"):
        if turntable:
            raise UsageError("--turntable: an SVG is one drawing; write a .gif, .mp4 or .png")
        if args.retina:
            write_exr(args.retina, retina)
        write_svg(args.output, retina, threads=args.threads,
                  **{**options, "background": _picture_options(scene, False)["background"]})
        if not args.quiet:
            print(f"wrote {args.output}" + (f" and {args.retina}" if args.retina else ""), file=sys.stderr)
        return 0
    bar.begin("compositing")
    picture = slice_picture(scene, retina, options, threads=args.threads)
    bar.update(1, 1)
    bar.end()
    if turntable:
        if args.retina:
            write_exr(args.retina, retina)
        paths = write_frames(args.output, picture, TURNTABLE_FPS, keep_frames=args.keep_frames)
        if not args.quiet:
            print("wrote " + (f"{len(paths)} frames {paths[0]} … {paths[-1]}" if len(paths) > 2
                              else " and ".join(paths)), file=sys.stderr)
        return 0

    # 3. Write (each file atomically).
    if args.retina:
        write_exr(args.retina, retina)
    _write_picture(args.output, picture, args.transparent)
    if not args.quiet:
        print(f"wrote {args.output}" + (f" and {args.retina}" if args.retina else ""), file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> None:
    given = sys.argv[1:] if argv is None else argv
    if given[:1] == ["view"]:  # a scene is a .toml or .py file, never "view"
        signal.signal(signal.SIGINT, signal.default_int_handler)  # see below
        code = view(given[1:])
        # A frame may still be tracing in the worker thread (the GIL released, in the core):
        # end the process now rather than finalize the interpreter under a running native
        # thread (which can crash at exit).
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    debug = "--debug" in given
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, _terminate)
    try:
        # Ctrl-C is a KeyboardInterrupt again from here on (during start-up, ndtrace's import
        # made it exit quietly with 130: `_interrupted_at_start_up`).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        code = run(argv)
    except KeyboardInterrupt as e:
        name = str(e)
        sys.stderr.write(f"\nndtrace: {'terminated by ' + name if name else 'interrupted'}\n")
        # 128 + the signal's number, as a shell reports a process that a signal stopped.
        code = 128 + (signal.Signals[name].value if name.startswith("SIG") else signal.SIGINT)
    except (UsageError, ValueError, OSError) as e:
        if debug:
            traceback.print_exc()
        sys.stderr.write(f"ndtrace: error: {e}\n")
        code = 2
    sys.exit(code)


if __name__ == "__main__":
    main()
