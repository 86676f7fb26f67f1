"""Viewer benchmark: frames per second of the drag loop of ``ndtrace view``.

Starts the viewer's server in this process on 127.0.0.1, connects a websocket client as the
page does, and drags: each step sends one rolling-ball move and waits for the draft frame it
causes (build the rotated scene + trace the draft retina + composite + encode JPEG + send over
the websocket + receive), so frames/s is one over the whole loop's time per frame, what a user
dragging the mouse sees. Prints, per scene, frames/s and the median time of each stage on the
server (build, trace, composite, encode), of the round trip, and the process's CPU time per
frame (user + system, all threads: on a machine shared with other work, frames/s follows the
cores it gets, while the CPU time per frame stays about the same).

Scenes: the tesseract, the 3-sphere and the 5-cube (``scenes/tesseract.toml``,
``sphere3.toml``, ``penteract.toml``) at the default draft resolution (about 32³ = 32768 retina
cells: 32³ in 4D, 14⁴ in 5D) and the default picture (512×512, drafts composited at 192×192).

Usage:  python bench/viewer.py [--frames 60] [--threads 2] [--draft-cells 32768] [--size 512]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import time
from pathlib import Path

import ndtrace
from ndtrace.viewer.server import HOST, make_app
from ndtrace.viewer.session import DRAFT_CELLS, ViewSession

SCENES = Path(__file__).resolve().parents[1] / "scenes"


async def drag_loop(scene: ndtrace.Scene, name: str, frames: int, warmup: int, **session) -> dict:
    from aiohttp import ClientSession, WSMsgType, web

    token = "bench"
    app = make_app(lambda: ViewSession(scene, name=name, **session), token)
    runner = web.AppRunner(app, access_log=None)
    await runner.setup()
    site = web.TCPSite(runner, HOST, 0)
    await site.start()
    port = runner.addresses[0][1]
    metas, loops = [], []
    try:
        async with ClientSession() as client:
            async with client.ws_connect(f"http://{HOST}:{port}/ws?token={token}", max_msg_size=0) as ws:
                seq = 0

                async def next_frame() -> dict:
                    while True:
                        msg = await ws.receive()
                        if msg.type == WSMsgType.BINARY:
                            n = int.from_bytes(msg.data[:4], "little")
                            meta = json.loads(msg.data[4:4 + n])
                            if meta["quality"] == "draft":
                                return meta
                        elif msg.type != WSMsgType.TEXT:
                            raise RuntimeError(f"websocket closed: {msg}")
                        elif json.loads(msg.data)["type"] == "error":
                            raise RuntimeError(msg.data)

                seq += 1
                await ws.send_str(json.dumps({"type": "hello", "seq": seq}))
                await next_frame()
                cpu0 = None
                for k in range(warmup + frames):
                    if k == warmup:
                        cpu0 = os.times()
                    seq += 1
                    t = time.perf_counter()
                    # A slow circle, 4 picture pixels per step, as a hand drags.
                    dx, dy = 4.0 * (1 if (k // 20) % 2 == 0 else -1), 2.0 * (1 if (k // 10) % 2 == 0 else -1)
                    await ws.send_str(json.dumps({"type": "roll", "seq": seq, "steps": [[dx, dy]]}))
                    meta = await next_frame()
                    if k >= warmup:
                        loops.append(time.perf_counter() - t)
                        metas.append(meta)
                cpu1 = os.times()
    finally:
        await runner.cleanup()
    cpu = (cpu1.user + cpu1.system - cpu0.user - cpu0.system) / len(loops)
    med = lambda key: statistics.median(m["timings"].get(key, 0.0) for m in metas)  # noqa: E731
    return {
        "fps": len(loops) / sum(loops), "cpu_ms": cpu * 1e3,
        "loop_ms": statistics.median(loops) * 1e3,
        "server_ms": statistics.median(m["ms"] for m in metas),
        "build_ms": med("build"), "trace_ms": med("trace"), "composite_ms": med("composite"),
        "encode_ms": med("encode"), "retina": metas[-1]["retina"], "picture": (metas[-1]["width"], metas[-1]["height"]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=60, help="timed frames per scene")
    ap.add_argument("--warmup", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--draft-cells", type=int, default=DRAFT_CELLS)
    ap.add_argument("--size", type=int, default=512, help="picture side")
    ap.add_argument("--draft-scale", type=float, default=None, help="draft picture / picture (default: the viewer's)")
    ap.add_argument("--scenes", nargs="*", default=["tesseract", "sphere3", "penteract"])
    a = ap.parse_args()
    print(f"drag loop of ndtrace view: {a.frames} frames per scene, {a.threads} threads, "
          f"draft ≈ {a.draft_cells} retina cells, picture {a.size}²")
    print(f"{'scene':<11} {'retina':>11} {'frames/s':>9} {'loop ms':>8} {'CPU ms':>7} {'server':>7} "
          f"{'build':>6} {'trace':>6} {'comp.':>6} {'encode':>6}")
    for name in a.scenes:
        scene = ndtrace.load_file(SCENES / f"{name}.toml")
        extra = {} if a.draft_scale is None else {"draft_scale": a.draft_scale}
        r = asyncio.run(drag_loop(scene, f"{name}.toml", a.frames, a.warmup, threads=a.threads,
                                  draft_cells=a.draft_cells, size=(a.size, a.size), **extra))
        print(f"{name:<11} {'×'.join(map(str, r['retina'])):>11} {r['fps']:9.1f} {r['loop_ms']:8.1f} "
              f"{r['cpu_ms']:7.1f} {r['server_ms']:7.1f} {r['build_ms']:6.1f} {r['trace_ms']:6.1f} {r['composite_ms']:6.1f} "
              f"{r['encode_ms']:6.1f}")


if __name__ == "__main__":
    main()
