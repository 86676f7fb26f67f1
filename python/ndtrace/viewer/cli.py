"""``ndtrace view SCENE``: the interactive viewer in the browser.

    ndtrace view scenes/tesseract.toml
    ndtrace view scenes/sphere3.toml --port 8765 --no-browser
    ndtrace view scenes/penteract.toml --size 640x640 --set composite.opacity=0.3

The first line on stdout is the page's URL, ``http://127.0.0.1:PORT/?token=TOKEN``; every
request must carry the token. Ctrl-C stops the server (exit status 0). Errors are one line
on stderr (exit status 2).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback

from .._command import UsageError, apply_sets, capped_threads, ints, load_scene
from .._ndtrace import __version__
from .._optional import need
from .server import serve


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="ndtrace view",
        description="View an N-dimensional scene (N = 3…6 and up) interactively in the browser: "
        "drag = the rolling ball (x–w / y–w for 4D), shift-drag = orbit the 3D view of the "
        "retina, wheel = zoom, a 4D arcball mode for N = 4.",
        epilog=__doc__.split("\n\n")[1] if __doc__ else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", help="a .toml scene, or a .py script defining scene() -> ndtrace.Scene")
    p.add_argument("--port", type=int, default=0, help="TCP port on 127.0.0.1 (0, the default: any free port)")
    p.add_argument("--no-browser", action="store_true", help="do not open the page in a browser")
    p.add_argument("--size", metavar="WxH", help="picture size in pixels (default: the scene's "
                   "[composite] size, else 512x512)")
    p.add_argument("--draft-cells", type=int, metavar="C",
                   help="retina cells of a draft frame while the mouse moves (default 32768 = 32³)")
    p.add_argument("--threads", type=int, help="worker threads (default: every core)")
    p.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a scene key as for `ndtrace SCENE -o …` (repeatable)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.add_argument("--version", action="version", version=f"ndtrace {__version__}")
    return p


def run(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port: expected 0 (any free port) to 65535, got {args.port}")
    args.threads = capped_threads(args.threads, "ndtrace view")
    if args.draft_cells is not None and args.draft_cells < 1:
        raise UsageError(f"--draft-cells: must be at least 1, got {args.draft_cells}")
    size = None
    if args.size:
        size = ints(args.size.lower(), "--size", "x")
        if len(size) != 2:
            raise UsageError(f"--size: expected WxH, got {args.size!r}")
    try:
        need("aiohttp", extra="view", what="ndtrace view")
    except ImportError as e:
        raise UsageError(str(e)) from None
    scene = load_scene(args.scene)
    scene = apply_sets(scene, args.set, scene._base or os.path.dirname(os.path.abspath(args.scene)))
    serve(scene, port=args.port, open_browser=not args.no_browser, name=os.path.basename(args.scene),
          size=(size[0], size[1]) if size else None, threads=args.threads, draft_cells=args.draft_cells)
    sys.stderr.write("ndtrace view: stopped\n")
    return 0


def main(argv: list[str]) -> int:
    try:
        return run(argv)
    except KeyboardInterrupt:
        sys.stderr.write("\nndtrace view: stopped\n")
        return 0
    except (UsageError, ValueError, OSError) as e:
        if "--debug" in argv:
            traceback.print_exc()
        sys.stderr.write(f"ndtrace view: error: {e}\n")
        return 2
