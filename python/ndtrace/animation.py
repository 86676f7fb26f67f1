"""Animations: a scene's ``[animation]`` rendered frame by frame to numbered PNGs, plus an
animated GIF (Pillow) or an MP4 (where ``imageio-ffmpeg`` is installed).

The ``[animation]`` table (``docs/scene-format.md``) names one rotation — a plane-angle
``sweep``, an SO(4) double-quaternion ``slerp`` or a ``rolling``-ball path — and what it moves
(the objects or the camera). Frame k is the scene with the rotation at t_k applied; the same
table drives ``ndtrace.animate``, the CLI's ``--frames`` and scripts::

    scene = ndtrace.load_file("scenes/tesseract_spin.toml")
    ndtrace.animate(scene, "spin.png")            # spin_0001.png … spin_0048.png + spin.gif
    ndtrace.animate(scene, "spin.gif", frames=12, animation={"sweep": {"plane": [1, 3],
                    "degrees": [0, 90]}})
"""

from __future__ import annotations

import os
import tempfile
from typing import Callable

import numpy as np

from .composite import composite as _composite
from .files import to_srgb8, write_png
from .retina import trace
from .scene import Scene, load_dict

__all__ = ["animate", "frame_scene", "frame_paths", "gif_frame_ms"]

VIDEOS = ("gif", "mp4", None)


def _table(scene: Scene, animation: dict | None, frames: int | None) -> Scene:
    """``scene`` with its animation table replaced by ``animation`` and ``frames`` set,
    validated (errors name the field, e.g. ``animation.sweep.plane``)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
    data = scene.to_dict()
    table = dict(animation) if animation is not None else data.get("animation")
    if table is None:
        raise ValueError(
            "the scene has no [animation] table: add one (docs/scene-format.md) or pass "
            "animation={...}"
        )
    if frames is not None:
        if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or frames < 1:
            raise ValueError(f"frames: expected a positive integer, got {frames!r}")
        table["frames"] = int(frames)
    data["animation"] = table
    return load_dict(data, base=scene._base)


def frame_scene(scene: Scene, k: int) -> Scene:
    """Frame ``k`` (0-based) of the scene's animation, as a still :class:`Scene`."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 0:
        raise ValueError(f"k: expected a frame index ≥ 0, got {k!r}")
    return load_dict(scene.compiled().animation_frame(int(k)), base=scene._base)


def frame_paths(output: str | os.PathLike, frames: int) -> list[str]:
    """The numbered PNG paths for ``output`` (``out.png`` → ``out_0001.png`` …; the video's
    extension is replaced likewise)."""
    stem, _ = os.path.splitext(os.fspath(output))
    digits = max(4, len(str(frames)))
    return [f"{stem}_{k + 1:0{digits}d}.png" for k in range(frames)]


def _video_kind(output: str, video: str | None) -> str | None:
    ext = os.path.splitext(output)[1].lower()
    if ext not in (".png", ".gif", ".mp4"):
        raise ValueError(f"output {output}: unknown extension: expected .png, .gif or .mp4")
    if video not in VIDEOS:
        raise ValueError(f"video: expected 'gif', 'mp4' or None, got {video!r}")
    kind = ext[1:] if ext != ".png" else video
    if kind == "mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                "MP4 output needs imageio-ffmpeg (pip install imageio-ffmpeg); "
                "write a .gif or numbered .png frames instead"
            ) from None
    folder = os.path.dirname(os.path.abspath(output))
    if not os.path.isdir(folder):
        raise ValueError(f"output {output}: folder {folder} does not exist")
    return kind


def gif_frame_ms(fps: float) -> int:
    """A GIF frame's duration: GIF counts in 1/100 s, and viewers slow frames shorter than
    2/100 s down, so 1/fps is rounded to 10 ms and kept at 20 ms or more (at most 50 fps)."""
    return 10 * max(2, round(100.0 / fps))


def _write_gif(path: str, frames: list[np.ndarray], fps: float) -> None:
    from PIL import Image

    images = [Image.fromarray(f, "RGB") for f in frames]
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".ndtrace-", suffix=".gif", dir=folder)
    os.close(fd)
    try:
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                       duration=gif_frame_ms(fps), loop=0)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _write_mp4(path: str, frames: list[np.ndarray], fps: float) -> None:
    import imageio_ffmpeg

    h, w = frames[0].shape[:2]
    # yuv420p needs even sides: repeat the last row/column where needed.
    ph, pw = h + h % 2, w + w % 2
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".ndtrace-", suffix=".mp4", dir=folder)
    os.close(fd)
    try:
        writer = imageio_ffmpeg.write_frames(tmp, (pw, ph), fps=fps, codec="libx264",
                                             pix_fmt_out="yuv420p", macro_block_size=2,
                                             output_params=["-y"])
        writer.send(None)
        for f in frames:
            f = np.pad(f, ((0, ph - h), (0, pw - w), (0, 0)), mode="edge")
            writer.send(np.ascontiguousarray(f).tobytes())
        writer.close()
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def animate(
    scene: Scene,
    output: str | os.PathLike,
    *,
    frames: int | None = None,
    animation: dict | None = None,
    video: str | None = "gif",
    threads: int | None = None,
    composite: dict | None = None,
    progress: Callable[[int, int], object] | None = None,
) -> list[str]:
    """Renders the scene's animation and returns the paths written.

    ``output`` is ``out.png`` (numbered frames ``out_0001.png`` … plus ``out.gif``, or
    ``out.mp4`` with ``video="mp4"``, or frames only with ``video=None``), ``out.gif`` or
    ``out.mp4`` (the numbered PNG frames are written beside it as well). ``animation`` replaces
    the scene's ``[animation]`` table (same keys) and ``frames`` its frame count. Each frame is
    traced, composited with the scene's ``[composite]`` options updated by ``composite``, and
    written atomically; ``progress(done, frames)`` is called after each frame. Ctrl-C stops
    between or inside frames: finished frames stay, the video is not written.
    """
    output = os.fspath(output)
    kind = _video_kind(output, video)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int) or threads < 1):
        raise ValueError(f"threads: expected a positive integer or None, got {threads!r}")
    animated = _table(scene, animation, frames)
    data = animated.to_dict()
    table = data["animation"]
    options = dict(data.get("composite") or {})
    options.setdefault("background", data["background"])
    options.update(composite or {})
    count = int(table["frames"])
    paths = frame_paths(output, count)
    video_frames: list[np.ndarray] = []
    for k, path in enumerate(paths):
        still = frame_scene(animated, k)
        picture = _composite(trace(still, threads=threads), threads=threads, **options)
        write_png(path, picture)
        if kind is not None:
            video_frames.append(to_srgb8(picture, opaque=True))
        if progress is not None:
            progress(k + 1, count)
    written = list(paths)
    if kind is not None:
        video_path = os.path.splitext(output)[0] + "." + kind
        (_write_gif if kind == "gif" else _write_mp4)(video_path, video_frames, float(table["fps"]))
        written.append(video_path)
    return written
