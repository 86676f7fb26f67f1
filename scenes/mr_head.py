"""A Python scene script: a real MR volume as a 4D elevation map.

The data is ``anatomical.nii``, a 33×41×25 T1-weighted MR image of a head at 2 mm voxels
(int16), shipped inside the nibabel package as test data (nibabel's MIT licence; see
nibabel's COPYING). Nothing is downloaded: the file is read from the installed package, through
the scene's NIfTI path (``field = "….nii"``, nibabel). Install it with
``pip install "ndtrace[nifti]"``.

The image intensity f becomes the height w = height·f of a hypersurface of R^4 over the head's
box, lit from a 4D direction so that the boundaries between tissues read as slopes, coloured
with matplotlib's ``bone`` map (keyed by the colour bar), with an isosurface marking at 70% of
the intensity range (around the white matter; marked on the colour bar). The camera is the
course's: orthographic, looking down the w axis, so the retina's x, y, z are the volume's. The
picture is the 3D retina with the octant toward the viewer cut away, beside three orthogonal
sections through it, titled by the plane each lies in.

Render it with:  ndtrace scenes/mr_head.py -o mr_head.png
"""

import os

import numpy as np

import ndtrace


def volume_path() -> str:
    """anatomical.nii inside the installed nibabel package."""
    try:
        import nibabel
    except ImportError:
        raise ImportError('scenes/mr_head.py needs nibabel: pip install "ndtrace[nifti]"') from None
    return os.path.join(os.path.dirname(nibabel.__file__), "tests", "data", "anatomical.nii")


def scene() -> ndtrace.Scene:
    path = volume_path()
    f = ndtrace.mesh.read_field(path)
    lo, top = (float(v) for v in np.percentile(f, [5, 99.5]))  # ignoring a few hot voxels
    return (
        ndtrace.Scene(4, ambient=[0.25, 0.25, 0.27])
        # The head's box is [−0.8, 0.8] × [−1, 1] × [−0.6, 0.6]: cubic cells, 52 × 64 × 40.
        .set_camera([0, 0, 0, 4], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                    projection="orthographic", extent=0.85, resolution=[52, 64, 40])
        .add_light("directional", direction=[0.9, 0.7, 0.3, 0.6])
        .add_object("elevation", field=path, height=0.4 / (top - lo), smooth=True, label="T1 intensity",
                    material={"colormap": "bone", "range": [lo, top], "specular": 0.15,
                              "isolines": {"values": [lo + 0.7 * (top - lo)], "width": 0.03,
                                           "color": [0.9, 0.35, 0.1]}})
        .set_composite(mode="volume", layout="sections",
                       cutaway={"shape": "box", "min": [0, 0, -1.5], "max": [1.5, 1.5, 0]},
                       title="An MR head as a 4D elevation map")
    )
