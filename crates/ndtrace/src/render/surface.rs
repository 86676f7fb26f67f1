//! The colour of a point of a surface drawn directly ([`crate::surface`], "bear hair"): the
//! lighting of the surface's thickening as its circles shrink to a point, whose means over a
//! tube's width are [`crate::surface::tube_diffuse`] and [`crate::surface::tube_specular`]
//! (course notes, Part II(B) "4D surfaces and points"), with the scene's lights and shadows.

use super::shade::{id_color, toward_light, SHADOW_OFFSET};
use crate::linalg::{add, dot, mat_vec, norm, scale, sub, Matrix, Rgb, Vector};
use crate::ray::Ray;
use crate::scene::desc::RenderMode;
use crate::scene::Scene;
use crate::surface::{tangent_projector, tube_diffuse, tube_specular, Surface};

/// The normal-plane part of `v` at a point of tangent projector `p`: v − P·v.
#[inline]
fn normal_part<const N: usize>(p: &Matrix<N>, v: &Vector<N>) -> Vector<N> {
    sub(v, &mat_vec(p, v))
}

/// (e, w) components of a normal-plane vector `v_n` in the frame of the unit `e`: e·v and the
/// length of the rest.
#[inline]
fn split<const N: usize>(v_n: &Vector<N>, e: &Vector<N>) -> (f64, f64) {
    let along = dot(v_n, e);
    (along, norm(&sub(v_n, &scale(e, along))).max(0.0))
}

/// A surface point to shade: its triangle's object and index, barycentric coordinates, the
/// point itself and the unit direction from the eye toward it.
pub(super) struct SurfacePoint<const N: usize> {
    pub obj: usize,
    pub tri: usize,
    pub bary: [f64; 3],
    pub x: Vector<N>,
    pub dir: Vector<N>,
    pub depth: f64,
}

/// The tangent projector at a surface point: the triangle's own (flat), or the barycentric mix
/// of its vertices' (smooth).
fn projector_at<const N: usize>(
    scene: &Scene<N>,
    s: &Surface<N>,
    pt: &SurfacePoint<N>,
) -> Matrix<N> {
    let o = &scene.objects[pt.obj];
    let t = s.triangles[pt.tri];
    if let Some(vt) = &s.vertex_tangents {
        let mut p = [[0.0; N]; N];
        for (k, &i) in t.iter().enumerate() {
            let m = &vt[i as usize];
            for r in 0..N {
                for c in 0..N {
                    p[r][c] += pt.bary[k] * m[r][c];
                }
            }
        }
        return p;
    }
    let [a, b, c] = t.map(|i| o.mesh.vertices[i as usize]);
    tangent_projector(&a, &b, &c).map_or([[0.0; N]; N], |(p, _)| p)
}

/// The colour of a surface point (the render mode's; for `shaded`, the limit lighting of the
/// module docs with the scene's ambient light, lights and hard shadows) and the unit normal ê
/// facing the eye, which the retina records.
pub(super) fn surface_color<const N: usize>(
    scene: &Scene<N>,
    surface: &Surface<N>,
    pt: &SurfacePoint<N>,
    depth_range: (f64, f64),
) -> (Rgb, Vector<N>) {
    let p = projector_at(scene, surface, pt);
    // ê = −d_𝒩/|d_𝒩|; when the eye looks along the tangent plane (d_𝒩 = 0), any normal will
    // do: the normal-plane part of the coordinate axis that has the largest one.
    let d_n = normal_part(&p, &pt.dir);
    let len = norm(&d_n);
    let e = if len > 1e-9 {
        scale(&d_n, -1.0 / len)
    } else {
        let best = (0..N)
            .map(|k| normal_part(&p, &std::array::from_fn(|i| (i == k) as u8 as f64)))
            .max_by(|a, b| norm(a).total_cmp(&norm(b)))
            .unwrap_or([0.0; N]);
        let l = norm(&best);
        if l > 0.0 {
            scale(&best, 1.0 / l)
        } else {
            best
        }
    };
    let m = &scene.objects[pt.obj].material;
    let color = match scene.render.mode {
        RenderMode::Shaded => {
            let v = scale(&pt.dir, -1.0);
            let eps = SHADOW_OFFSET * scene.extent;
            let mut c: Rgb = std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * m.color[k]);
            for light in &scene.lights {
                let Some(to) = toward_light(light, &pt.x) else {
                    continue;
                };
                let l = to.dir;
                let (l_e, l_w) = split(&normal_part(&p, &l), &e);
                let diffuse = tube_diffuse(l_e, l_w);
                let spec = if m.specular.iter().any(|&k| k != 0.0) {
                    let h = add(&l, &v);
                    let hl = norm(&h);
                    let h = if hl > 0.0 { scale(&h, 1.0 / hl) } else { l };
                    let (h_e, h_w) = split(&normal_part(&p, &h), &e);
                    tube_specular(h_e, h_w, m.shininess)
                } else {
                    0.0
                };
                if diffuse <= 0.0 && spec <= 0.0 {
                    continue;
                }
                if scene.render.shadows {
                    let ray = Ray {
                        origin: crate::linalg::add_scaled(&pt.x, eps, &l),
                        dir: l,
                    };
                    if scene
                        .instances
                        .any_hit(&ray, 0.0, to.dist - eps, &|_| true, 0..0)
                    {
                        continue;
                    }
                }
                for k in 0..3 {
                    c[k] += to.atten
                        * to.color[k]
                        * (m.diffuse[k] * m.color[k] * diffuse + m.specular[k] * spec);
                }
            }
            c
        }
        RenderMode::Depth => {
            let g = 1.0
                - 0.8
                    * ((pt.depth - depth_range.0) / (depth_range.1 - depth_range.0))
                        .clamp(0.0, 1.0);
            [g; 3]
        }
        RenderMode::Normal => std::array::from_fn(|k| if k < N { 0.5 + 0.5 * e[k] } else { 0.5 }),
        RenderMode::PrimitiveId => id_color(pt.tri as u32 ^ 0x8000_0000),
        RenderMode::Barycentric => pt.bary,
    };
    (color, e)
}
