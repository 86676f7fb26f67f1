"""Golden-image regression renders of every gallery scene and of the debug modes.

Each scene is rendered small (32³ retina for N = 4, 12⁴ for N = 5, 128² for N = 3, 256 for
N = 2) and composited to 256 × 256 with the scene's own [composite] settings, converted to
8-bit sRGB exactly as transparent PNG output is (alpha kept, so that coverage is compared too),
and compared with tests/golden/<name>.png: a pixel may
differ by at most TOLERANCE in any channel, and at most OUTLIERS of the pixels may exceed it.
On failure the actual, reference and difference images are written to tests/golden-failures/
(git-ignored). ``pytest --update-golden`` regenerates the references; a reference changes only
with its reason in the commit message.
"""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest

import ndtrace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GOLDEN = os.path.join(ROOT, "tests", "golden")
FAILURES = os.path.join(ROOT, "tests", "golden-failures")
TOLERANCE = 6  # 8-bit levels per channel
OUTLIERS = 0.005  # fraction of pixels allowed beyond TOLERANCE

SMALL = {2: 256, 3: 128, 4: 32, 5: 12, 6: 6, 7: 4, 8: 3}
SCENES = sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml")) + glob.glob(os.path.join(ROOT, "scenes", "*.py")))
CASES = [(os.path.splitext(os.path.basename(p))[0], p, None) for p in SCENES] + [
    ("tesseract-depth", os.path.join(ROOT, "scenes", "tesseract.toml"), "depth"),
    ("tesseract-normal", os.path.join(ROOT, "scenes", "tesseract.toml"), "normal"),
    ("cube-depth", os.path.join(ROOT, "scenes", "cube.toml"), "depth"),
    ("cube-normal", os.path.join(ROOT, "scenes", "cube.toml"), "normal"),
]


def load_scene(path: str) -> ndtrace.Scene:
    if path.endswith(".py"):
        import runpy

        return runpy.run_path(path)["scene"]()
    return ndtrace.load_file(path)


def render_small(path: str, mode: str | None) -> np.ndarray:
    """The scene at golden size, as 8-bit sRGB RGBA (H, W, 4)."""
    scene = load_scene(path)
    data = scene.to_dict()
    data["camera"]["resolution"] = SMALL[data["dim"]]
    data.setdefault("render", {})["samples"] = 1
    if mode:
        data["render"]["mode"] = mode
    comp = dict(data.pop("composite", None) or {})
    if data["dim"] >= 4:
        comp["size"] = (256, 256)
    scene = ndtrace.load_dict(data, base=os.path.dirname(path))
    picture = ndtrace.composite(ndtrace.trace(scene), **comp)
    return to_srgb8(picture)


def to_srgb8(rgba: np.ndarray) -> np.ndarray:
    """Premultiplied linear RGBA → 8-bit sRGB with straight alpha (as
    ``ndtrace.write_png(..., transparent=True)``: the references keep alpha)."""
    a = np.clip(rgba[..., 3:4], 0.0, 1.0)
    straight = np.where(a > 0, rgba[..., :3] / np.where(a > 0, a, 1.0), 0.0)
    x = np.clip(straight, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    out = np.concatenate([srgb, a], axis=-1)
    return (out * 255.0 + 0.5).astype(np.uint8)


def read_png(path: str) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA"))


@pytest.mark.parametrize("name,path,mode", CASES, ids=[c[0] for c in CASES])
def test_golden(name, path, mode, request):
    actual = render_small(path, mode)
    reference = os.path.join(GOLDEN, f"{name}.png")
    if request.config.getoption("--update-golden"):
        from PIL import Image

        os.makedirs(GOLDEN, exist_ok=True)
        Image.fromarray(actual).save(reference)
        return
    if not os.path.exists(reference):
        pytest.fail(f"missing reference {reference}: run pytest --update-golden and commit it")
    expected = read_png(reference)
    ok, message = compare(actual, expected)
    if not ok:
        os.makedirs(FAILURES, exist_ok=True)
        from PIL import Image

        Image.fromarray(actual).save(os.path.join(FAILURES, f"{name}-actual.png"))
        Image.fromarray(expected).save(os.path.join(FAILURES, f"{name}-reference.png"))
        if actual.shape == expected.shape:
            diff = np.abs(actual.astype(int) - expected.astype(int)).max(axis=-1)
            Image.fromarray(np.clip(diff * 8, 0, 255).astype(np.uint8)).save(
                os.path.join(FAILURES, f"{name}-difference.png"))
        pytest.fail(f"{name}: {message}; images written to {FAILURES}")


def compare(actual: np.ndarray, expected: np.ndarray) -> tuple[bool, str]:
    if actual.shape != expected.shape:
        return False, f"shape {actual.shape} differs from the reference's {expected.shape}"
    diff = np.abs(actual.astype(int) - expected.astype(int)).max(axis=-1)
    bad = float(np.mean(diff > TOLERANCE))
    if bad > OUTLIERS:
        return False, f"{bad:.2%} of pixels differ by more than {TOLERANCE} levels (budget {OUTLIERS:.2%})"
    return True, ""


def test_comparison_catches_real_differences():
    """The comparison itself can fail: a shifted picture and a darkened one are caught."""
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, size=(64, 64, 4), dtype=np.uint8)
    assert compare(img, img)[0]
    assert not compare(np.roll(img, 3, axis=1), img)[0]
    darker = img.copy()
    darker[..., :3] //= 2
    assert not compare(darker, img)[0]
    assert not compare(img[:32], img)[0]
    noisy = img.astype(int)
    noisy[0, 0, 0] = (noisy[0, 0, 0] + 128) % 256  # one outlier is within the budget
    assert compare(noisy.astype(np.uint8), img)[0]
