//! The lighting of a surface point as the limit of its thickening (course notes Part II(B):
//! "Calculate the light that would be reflected from a surface if you attached shiny circles and
//! shrunk them to a point").
//!
//! Thickened, a surface point carries a small circle in its 2D normal plane 𝒩, whose unit
//! normals are n(φ) ∈ 𝒩. A ray from the eye whose direction has the component d_𝒩 in 𝒩 meets
//! the tube T × circle at the circle point whose normal makes the angle φ with ê =
//! −d_𝒩/|d_𝒩| (the normal facing the eye); rays spread evenly across the tube's width meet it at
//! offsets s = sin φ, so the tube's visible half contributes with the weight ds = cos φ dφ,
//! φ ∈ (−π/2, π/2). With n(φ) = cos φ·ê + sin φ·ŵ (ŵ ⊥ ê in 𝒩), the mean over the tube's
//! width of a term f(n) is
//!
//! ```text
//! ⟨f⟩ = ½ ∫_{−π/2}^{π/2} f(n(φ)) cos φ dφ.
//! ```
//!
//! Only the light's component L_𝒩 in the normal plane reaches the circle's normals
//! (n·L = n·L_𝒩): written l_e = L_𝒩·ê, l_w = |L_𝒩 − l_e ê| and α = atan2(l_w, l_e) ∈ [0, π]
//! (the angle between L_𝒩 and ê), the Lambert term max(0, n·L) averages to
//!
//! ```text
//! ⟨max(0, n·L)⟩ = |L_𝒩| (sin α + (π − α) cos α) / 4 = (l_w + (π − α)·l_e) / 4     (tube_diffuse)
//! ```
//!
//! (π/4·|L_𝒩| for a light behind the eye, 0 for one straight behind the tube), and the
//! Blinn–Phong term ⟨max(0, n·ĥ)^s⟩ is the same mean of the half vector's component h_𝒩, by
//! quadrature ([`tube_specular`]). A surface point is then lit as the mesh's points are
//! ([`crate::render::shade_hit`]) with these means in place of n̂·l̂ and max(0, n̂·ĥ)^s; these are
//! the colours the thickened surface's cells average to as the radius shrinks (tested against
//! traced thickenings).

use super::Surface;
use crate::linalg::{add, dot, mat_vec, norm, scale, sub, Matrix, Vector};
use crate::ray::Ray;
use crate::render::shade::{id_color, toward_light};
use crate::scene::build::Rgb;
use crate::scene::desc::RenderMode;
use crate::scene::Scene;
use std::f64::consts::PI;

/// The mean of max(0, n·L) over a tube's visible width: (l_w + (π − α)·l_e)/4 with
/// α = atan2(l_w, l_e), for the light's normal-plane component L_𝒩 = l_e·ê + l_w·ŵ (l_w ≥ 0)
/// and ê the normal facing the eye (module docs).
pub fn tube_diffuse(l_e: f64, l_w: f64) -> f64 {
    let alpha = l_w.atan2(l_e);
    ((l_w + (PI - alpha) * l_e) / 4.0).max(0.0)
}

/// Samples of [`tube_specular`]'s quadrature.
const SPECULAR_SAMPLES: usize = 64;

/// The mean of max(0, n·ĥ)^s over a tube's visible width, ½∫ max(0, cos φ·h_e + sin φ·h_w)^s
/// cos φ dφ over φ ∈ (−π/2, π/2), for the half vector's normal-plane component h_e·ê + h_w·ŵ
/// (h_w ≥ 0): 1 for s = 0 (x⁰ = 1, as on meshes), otherwise the midpoint rule on the part of the interval where
/// the integrand exceeds about e⁻²⁴ of its peak.
pub fn tube_specular(h_e: f64, h_w: f64, s: f64) -> f64 {
    let rho = h_e.hypot(h_w);
    if !(rho > 0.0) {
        return 0.0;
    }
    // cos φ·h_e + sin φ·h_w = ρ cos(φ − β), positive for |φ − β| < π/2.
    let beta = h_w.atan2(h_e);
    if s == 0.0 {
        // x⁰ = 1 even where n·ĥ ≤ 0, as for meshes ([`crate::render::shade_hit`]).
        return 1.0;
    }
    let reach = (7.0 / (s + 1.0).sqrt()).min(PI / 2.0);
    let lo = (beta - reach).max(-PI / 2.0);
    let hi = (beta + reach).min(PI / 2.0);
    if !(hi > lo) {
        return 0.0;
    }
    let step = (hi - lo) / SPECULAR_SAMPLES as f64;
    let peak = rho.powf(s);
    let mut sum = 0.0;
    for k in 0..SPECULAR_SAMPLES {
        let phi = lo + (k as f64 + 0.5) * step;
        let c = (phi - beta).cos();
        if c > 0.0 {
            sum += c.powf(s) * phi.cos();
        }
    }
    0.5 * peak * sum * step
}

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
    super::tangent_projector(&a, &b, &c).map_or([[0.0; N]; N], |(p, _)| p)
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
            let eps = crate::render::shade::SHADOW_OFFSET * scene.extent;
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
                        .any_hit(&ray, 0.0, to.dist - eps, |_| true, 0..0)
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
