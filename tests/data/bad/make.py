"""Writes the hostile files of this folder (run it from anywhere; needs numpy and OpenEXR).

Each file is tiny and asks for something the readers must refuse with the error that
tests/test_hostile.py expects (listed in README.md beside them).
"""

import os
import struct

import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name: str, header: dict, channels: dict) -> bytes:
    path = os.path.join(HERE, name)
    with OpenEXR.File(header, channels) as f:
        f.write(path)
    with open(path, "rb") as f:
        return f.read()


def retina_channels(dim: int, w: int, h: int, object_id: int = 0) -> dict:
    ch = {n: np.zeros((h, w), np.float32) for n in ["R", "G", "B", "A", "Z"]}
    ch.update({f"N.{a}": np.zeros((h, w), np.float32) for a in range(dim)})
    ch["objectId"] = np.full((h, w), object_id, np.uint32)
    ch["primitiveId.lo"] = np.zeros((h, w), np.uint32)
    ch["primitiveId.hi"] = np.zeros((h, w), np.uint32)
    return ch


def patch_windows(data: bytes, x_max: int, y_max: int) -> bytes:
    """Both windows of a single-part file made (0, 0)–(x_max, y_max) (same length)."""
    for name in (b"dataWindow\0box2i\0", b"displayWindow\0box2i\0"):
        at = data.index(name) + len(name) + 4
        data = data[:at] + struct.pack("<4i", 0, 0, x_max, y_max) + data[at + 16:]
    return data


def main() -> None:
    scan = {"type": OpenEXR.scanlineimage}
    rgba = {c: np.zeros((5, 4), np.float32) for c in "RGBA"}
    # A picture whose header declares 100001 × 100001 pixels (160 GB of samples) in 0.6 KB.
    small = write("exr-data-window.exr", {**scan, "compression": OpenEXR.ZIP_COMPRESSION}, rgba)
    with open(os.path.join(HERE, "exr-data-window.exr"), "wb") as f:
        f.write(patch_windows(small, 100000, 100000))
    # The same, uncompressed, declaring 400 × 300 pixels: more samples than the file holds.
    small = write("exr-truncated.exr", {**scan, "compression": OpenEXR.NO_COMPRESSION}, rgba)
    with open(os.path.join(HERE, "exr-truncated.exr"), "wb") as f:
        f.write(patch_windows(small, 399, 299))
    # A retina whose shape attribute asks for 10^15 cells.
    write("retina-shape.exr", {**scan, "compression": OpenEXR.ZIP_COMPRESSION, "ndtrace.dim": 4,
                               "ndtrace.retinaShape": "100000,100000,100000", "ndtrace.slice": 0},
          retina_channels(4, 7, 1))
    # A retina whose objectId (id + 1) is 2^31 + 5: no i32 object index.
    write("retina-object-id.exr", {**scan, "compression": OpenEXR.ZIP_COMPRESSION, "ndtrace.dim": 2,
                                   "ndtrace.retinaShape": "7", "ndtrace.slice": 0},
          retina_channels(2, 7, 1, 2**31 + 5))
    # A retina whose dimension attribute is negative.
    write("retina-dim.exr", {**scan, "compression": OpenEXR.ZIP_COMPRESSION, "ndtrace.dim": -3,
                             "ndtrace.retinaShape": "7", "ndtrace.slice": 0},
          retina_channels(2, 7, 1))


if __name__ == "__main__":
    main()
