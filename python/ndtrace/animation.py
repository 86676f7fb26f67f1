"""Animations: a scene's ``[animation]`` rendered frame by frame to numbered PNGs, plus an
animated GIF (Pillow) or an MP4 (where ``imageio-ffmpeg`` is installed).

The ``[animation]`` table (``docs/scene-format.md``) names one rotation — a plane-angle
``sweep``, an SO(4) double-quaternion ``slerp`` or a ``rolling``-ball path — and what it moves
(the objects or the camera). Frame k is the scene with the rotation at t_k applied; the same
table drives ``ndtrace.animate``, the CLI's ``--frames`` and scripts::

    scene = ndtrace.load_file("scenes/tesseract_spin.toml")
    ndtrace.animate(scene, "spin.gif")            # spin.gif (keep_frames=True: + spin_0001.png …)
    ndtrace.animate(scene, "spin.png")            # spin_0001.png … spin_0024.png + spin.gif
    ndtrace.animate(scene, "spin.gif", frames=12, animation={"sweep": {"plane": [1, 3],
                    "degrees": [0, 90]}})
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np

from . import _ndtrace
from ._dask import render_frames
from ._description import plain_scene, scene_reader
from ._optional import need
from ._util import output_done, output_temp
from .composite import scene_options
from .files import to_srgb8, write_png
from .retina import trace
from .scene import Scene, load_dict
from .slicing import picture as slice_picture, slice_options, sliced

__all__ = ["animate", "frame_scene", "frame_paths", "gif_frame_ms", "render_frame",
           "GIF_MEMORY_LIMIT"]

VIDEOS = ("gif", "mp4", None)


def _reanimated(scene: Scene, data: dict) -> Scene:
    """``data`` — ``scene``'s description with another ``[animation]`` table — as a scene that
    shares ``scene``'s build when nothing else differs (else built anew, as :func:`load_dict`)."""
    compiled = _ndtrace.load_dict(plain_scene(data, "<dict>"), "<dict>", scene._base, scene_reader,
                                  scene.compiled())
    return Scene._from_compiled(compiled, scene._base)


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
    return _reanimated(scene, data)


def frame_scene(scene: Scene, k: int) -> Scene:
    """Frame ``k`` (0-based) of the scene's animation, as a still :class:`Scene`, without a
    rebuild of the BVH: when the animation moves the camera the frame shares the scene's built
    objects and BVH, when it moves objects it shares the BVHs, which hold each object in its own
    space, and moves the rays instead; a frame that cannot (objects read from files, a
    transform turning handedness around) is built from its description."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k < 2**32:
        raise ValueError(f"k: expected a frame index ≥ 0, got {k!r}")
    compiled = scene.compiled()
    # The same bits as a build of the frame's description.
    shared = compiled.reused_frame(int(k))
    if shared is not None:
        return Scene._from_compiled(shared, scene._base)
    return load_dict(compiled.animation_frame(int(k)), base=scene._base)


def render_frame(animated: Scene, k: int, threads: int | None, options: dict,
                 progress: Callable[[int, int], object] | None = None) -> np.ndarray:
    """Frame ``k`` of ``animated``'s animation traced and composited with ``options``: the
    picture ``animate`` writes (here or on a Dask worker)."""
    still = frame_scene(animated, k)
    if (cut := sliced(still, options.get("size"))) is not still:
        # A [slice] (or a slice sweep): the frame is the (N−1)-D slice.
        options = slice_options(options, cut.dim)
        still = cut
    return slice_picture(still, trace(still, threads=threads, progress=progress), options,
                         threads=threads)


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
            need("imageio_ffmpeg", extra="video", what="MP4 output", package="imageio-ffmpeg")
        except ImportError as e:
            raise ValueError(f"{e}; write a .gif or numbered .png frames instead") from None
    folder = os.path.dirname(os.path.abspath(output))
    if not os.path.isdir(folder):
        raise ValueError(f"output {output}: folder {folder} does not exist")
    return kind


def gif_frame_ms(fps: float) -> int:
    """A GIF frame's duration: GIF counts in 1/100 s, and viewers slow frames shorter than
    2/100 s down, so 1/fps is rounded to 10 ms and kept at 20 ms or more (at most 50 fps)."""
    return 10 * max(2, round(100.0 / fps))


#: Largest memory (bytes) the GIF's palette frames may take: a GIF is written at the end, so its
#: frames are held (one byte per pixel each); longer animations need MP4 or PNG frames only.
GIF_MEMORY_LIMIT = 1 << 30


class _Video:
    """A GIF or MP4 written frame by frame into a temporary file beside ``path``, renamed
    into place by :meth:`finish` and removed by :meth:`abort` (nothing half-written remains)."""

    def __init__(self, kind: str, path: str, fps: float) -> None:
        self.kind, self.path, self.fps = kind, path, fps
        self.tmp = output_temp(path, "." + kind)
        self.frames: list = []  # GIF: palette images
        self.writer: Any = None  # MP4: imageio-ffmpeg's generator
        self.size: tuple[int, int] | None = None

    def add(self, rgb: np.ndarray) -> None:
        h, w = rgb.shape[:2]
        if self.kind == "gif":
            from PIL import Image

            self.frames.append(Image.fromarray(rgb, "RGB").quantize(256, dither=Image.Dither.NONE))
            return
        import imageio_ffmpeg

        # yuv420p needs even sides: repeat the last row/column where needed.
        ph, pw = h + h % 2, w + w % 2
        if self.writer is None:
            self.size = (pw, ph)
            self.writer = imageio_ffmpeg.write_frames(
                self.tmp, (pw, ph), fps=self.fps, codec="libx264", pix_fmt_out="yuv420p",
                macro_block_size=2, output_params=["-y"])
            self.writer.send(None)
        padded = np.pad(rgb, ((0, ph - h), (0, pw - w), (0, 0)), mode="edge")
        self.writer.send(np.ascontiguousarray(padded).tobytes())

    def finish(self) -> None:
        if self.kind == "gif":
            first, *rest = self.frames
            first.save(self.tmp, format="GIF", save_all=True, append_images=rest,
                       duration=gif_frame_ms(self.fps), loop=0)
        else:
            self.writer.close()
        output_done(self.tmp, self.path)

    def abort(self) -> None:
        if self.writer is not None:
            try:
                self.writer.close()
            except Exception:  # noqa: BLE001 - the original error matters more
                pass
        if os.path.exists(self.tmp):
            os.unlink(self.tmp)


def write_frames(output: str | os.PathLike, frames: np.ndarray, fps: float, *,
                 keep_frames: bool = False) -> list[str]:
    """Writes pictures ``(F, H, W, 4)`` (e.g. ``composite(..., turntable=F)``) as ``out.gif`` or
    ``out.mp4`` (with ``keep_frames`` also the numbered PNG frames beside it) or as numbered
    frames ``out_0001.png`` … for ``out.png``; returns the paths written. Files appear
    atomically; nothing is left half-written on an error or Ctrl-C."""
    output = os.fspath(output)
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 4 or len(frames) == 0:
        raise ValueError(f"frames: expected pictures of shape (F, H, W, 4), got {frames.shape}")
    ext = os.path.splitext(output)[1].lower()
    kind = {".gif": "gif", ".mp4": "mp4"}.get(ext)
    if kind is None and ext != ".png":
        raise ValueError(f"output {output}: expected a .gif, .mp4 or .png path")
    if kind:
        _video_kind(output, kind)
    paths = frame_paths(output, len(frames))
    write_pngs = keep_frames or kind is None
    movie = _Video(kind, output, float(fps)) if kind else None
    try:
        for path, picture in zip(paths, frames):
            if write_pngs:
                write_png(path, picture)
            if movie is not None:
                movie.add(to_srgb8(picture, opaque=True))
        if movie is not None:
            movie.finish()
    except BaseException:
        if movie is not None:
            movie.abort()
        raise
    return (paths if write_pngs else []) + ([movie.path] if movie is not None else [])


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
    keep_frames: bool = False,
    client=None,
) -> list[str]:
    """Renders the scene's animation and returns the paths written.

    ``output`` is ``out.png`` (numbered frames ``out_0001.png`` … plus ``out.gif``, or
    ``out.mp4`` with ``video="mp4"``, or frames only with ``video=None``), ``out.gif`` or
    ``out.mp4`` (just the video; with ``keep_frames`` the numbered PNG frames are written beside
    it as well). Frames are opaque, as the video shows them. ``animation`` replaces
    the scene's ``[animation]`` table (same keys) and ``frames`` its frame count. Each frame is
    traced, composited with the scene's ``[composite]`` options updated by ``composite``, and
    written atomically; the MP4 is encoded as frames arrive, the GIF (palette frames, at most
    :data:`GIF_MEMORY_LIMIT` bytes) at the end. ``progress(done, total)`` counts retina cells
    over all frames. Ctrl-C stops within a fraction of a second: finished frames stay, the
    video is not written.

    ``client`` (a ``dask.distributed.Client``) renders the frames on its workers (each with
    ``threads`` threads, default 1: one per worker thread) and writes them here, in order: the same files,
    bit for bit (:mod:`ndtrace.cluster`); progress then counts finished frames.
    """
    output = os.fspath(output)
    kind = _video_kind(output, video)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int) or threads < 1):
        raise ValueError(f"threads: expected a positive integer or None, got {threads!r}")
    animated = _table(scene, animation, frames)
    data = animated.to_dict()
    table = data["animation"]
    options = scene_options(data)
    options.update(composite or {})
    options.pop("turntable", None)  # a frame of an animation is one picture
    count = int(table["frames"])
    cells = int(np.prod(animated.retina_shape))
    if kind == "gif":
        width, height = options.get("size") or (512, 512)
        if count * int(width) * int(height) > GIF_MEMORY_LIMIT:
            raise ValueError(
                f"a GIF of {count} frames of {width}×{height} would hold "
                f"{count * int(width) * int(height) / 2**30:.1f} GiB: write an MP4 "
                "(video='mp4') or PNG frames only (video=None), or use fewer frames")
    paths = frame_paths(output, count)
    write_frames = bool(keep_frames) or output.lower().endswith(".png")
    movie = _Video(kind, os.path.splitext(output)[0] + "." + kind, float(table["fps"])) if kind else None

    def write(k: int, picture: np.ndarray) -> None:
        if write_frames:
            write_png(paths[k], picture)
        if movie is not None:
            movie.add(to_srgb8(picture, opaque=True))

    try:
        if client is not None:
            render_frames(animated, count, client, threads, options, cells, progress, write,
                          render_frame)
        else:
            for k in range(count):
                tick = None if progress is None else (lambda done, _total, k=k: progress(k * cells + done, count * cells))
                write(k, render_frame(animated, k, threads, options, tick))
                if progress is not None:
                    progress((k + 1) * cells, count * cells)
        if movie is not None:
            movie.finish()
    except BaseException:
        if movie is not None:
            movie.abort()
        raise
    return (paths if write_frames else []) + ([movie.path] if movie is not None else [])
