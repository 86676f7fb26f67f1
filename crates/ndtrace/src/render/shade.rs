//! Shading one camera ray's nearest hit: N-D Lambert + Blinn–Phong with ambient light and hard
//! shadows (course notes, "Normals and the Cross-Product" and Part II(B) "4D Shading"), and the
//! colours of the debug render modes.
//!
//! [`shade_hit`] states the lighting model plainly, one ray and one light at a time. The tracer
//! shades whole groups of rays at once (`packets.rs`), with the same helpers and the same order
//! of every sum, so that each of its rays gets [`shade_hit`]'s bits (tested cell by cell).

use super::sampling::SplitMix;
use crate::accel::{BOX_PAD, PLANE_ROUNDING};
use crate::linalg::Rgb;
use crate::linalg::{add, add_scaled, dot, norm, scale, sub, Vector};
use crate::ray::{Hit, Ray};
use crate::scene::desc::Shading;
use crate::scene::{Light, Scene};

/// Shadow rays start this fraction of the scene's diagonal off the surface, toward the light.
/// The inside test widens every simplex, within its hyperplane, by its `BARY_SLACK` band: at
/// most `BOX_PAD` of the simplex's extent, so of the scene's, beyond its boundary; and a hit
/// point lies on the hyperplane of the simplex's rows as the tree stores them (rounded to
/// f32), within `PLANE_ROUNDING` of the simplex's extent of its exact hyperplane. A hit in
/// that band just past a convex ridge, moved off by ten times the band or more beyond that
/// rounding (checked at compile time), lies on the outer side of the neighbouring simplex too,
/// for folds up to atan(10) ≈ 84° between the two hyperplanes; so the shadow ray does not
/// start behind it.
pub const SHADOW_OFFSET: f64 = 2e-7;
const _: () = assert!(SHADOW_OFFSET >= 10.0 * BOX_PAD + PLANE_ROUNDING);

/// The colour of the camera ray `ray` at its nearest hit `hit` in `scene` (the `shaded` render
/// mode): N-D Lambert + Blinn–Phong with ambient light and hard shadows.
///
/// With x = o + t·d the hit point, n̂ its unit shading normal (the simplex's, or interpolated
/// from vertex normals for a smooth material; turned toward the viewer when two-sided),
/// v̂ = −d/|d| the unit vector toward the viewer, C, k_a, k_d, k_s and s the material's colour,
/// ambient, diffuse and specular coefficients and shininess, and A the scene's ambient light:
///
/// ```text
/// c = k_a ∘ A ∘ C + Σ_L  a_L · I_L ∘ (k_d ∘ C · (n̂·l̂) + k_s · max(0, n̂·ĥ)^s)
/// ```
///
/// summed in this order, over the lights L in scene order whose unit vector l̂ from x faces the
/// surface (n̂·l̂ > 0: the course's intensity, "the dot product of the illumination vector
/// with the normal … set to zero if it is negative", after eq. 6) and that no simplex
/// shadows. I_L is the
/// light's colour; a light at distance r has attenuation a_L = r^(−falloff) (1 for a
/// directional light); ĥ = (l̂ + v̂)/|l̂ + v̂| is the Blinn–Phong half vector (l̂ when that sum
/// is zero). The shadow ray of L leaves x toward the light from [`SHADOW_OFFSET`] times the
/// scene's diagonal off the simplex's hyperplane, on the light's side, and L is shadowed when
/// it meets any simplex before the light (culled ones too).
pub fn shade_hit<const N: usize>(scene: &Scene<N>, ray: &Ray<N>, hit: &Hit<N>) -> Rgb {
    let (obj, local) = scene.locate(hit.prim);
    let m = &scene.objects[obj].material;
    let n = shading_normal(scene, hit, obj, local, ray);
    let x = ray.at(hit.t);
    let v = scale(&ray.dir, -1.0 / norm(&ray.dir));
    let eps = SHADOW_OFFSET * scene.extent;
    let color = hit_color(scene, obj, local, hit, ray).unwrap_or(m.color);
    // Ambient: k_a ∘ A ∘ C.
    let mut c: Rgb = std::array::from_fn(|k| m.ambient[k] * scene.ambient[k] * color[k]);
    for light in &scene.lights {
        let Some(to_light) = toward_light(light, &x) else {
            continue;
        };
        let l = to_light.dir;
        // Lights behind the surface contribute nothing.
        let ndl = dot(&n, &l);
        let gouraud = (scene.render.shading == Shading::Gouraud).then(|| {
            let flip = super::gouraud::flipped(scene, hit, ray);
            let specular = m.specular.iter().any(|&s| s > 0.0);
            super::gouraud::factors(scene, (obj, local), hit, flip, |x, n| {
                vertex_factors(scene, light, x, n, m.shininess, specular)
            })
        });
        if gouraud.map_or(ndl <= 0.0, |(d, s)| d <= 0.0 && s <= 0.0) {
            continue;
        }
        if scene.render.shadows {
            let along = dot(&hit.normal, &l) >= 0.0;
            let (shadow, tmax) = shadow_ray(&x, &hit.normal, along, &l, to_light.dist, eps);
            if scene.instances.any_hit(&shadow, 0.0, tmax, &|_| true, 0..0)
                && (!scene.clips.active() || super::clip::blocks(scene, &shadow, tmax, &(0..0)))
            {
                continue;
            }
        }
        let diffuse: Rgb = std::array::from_fn(|k| m.diffuse[k] * color[k]);
        let term = match gouraud {
            None => {
                let spec = blinn_phong(&n, &l, &v, m.shininess);
                light_term(&to_light, &diffuse, ndl, &m.specular, spec)
            }
            // The factors carry the attenuation at each vertex.
            Some((d, spec)) => light_term(&to_light.unattenuated(), &diffuse, d, &m.specular, spec),
        };
        for k in 0..3 {
            c[k] += term[k];
        }
    }
    c
}

/// The colour C at a hit on simplex `local` of object `obj` when the object has a texture
/// ([`crate::texture`]); `None` when C is the material's colour everywhere.
#[inline(always)]
pub(super) fn hit_color<const N: usize>(
    scene: &Scene<N>,
    obj: usize,
    local: usize,
    hit: &Hit<N>,
    ray: &Ray<N>,
) -> Option<Rgb> {
    let o = &scene.objects[obj];
    let t = o.texture.as_ref()?;
    // The N-D depth only for `color_by = "depth"`.
    let depth = match t.depth {
        Some(_) => scene.camera.depth(hit.t, norm(&ray.dir)),
        None => 0.0,
    };
    Some(t.color(
        &o.material.color,
        &o.mesh,
        local,
        &hit.bary,
        &ray.at(hit.t),
        depth,
    ))
}

/// The unit shading normal at a hit on simplex `local` of object `obj`: flat (eq. 6) or
/// interpolated from vertex normals with the hit's barycentric coordinates; turned toward the
/// viewer for two-sided lighting.
#[inline(always)]
pub(super) fn shading_normal<const N: usize>(
    scene: &Scene<N>,
    hit: &Hit<N>,
    obj: usize,
    local: usize,
    ray: &Ray<N>,
) -> Vector<N> {
    let flat = hit.normal;
    let mut n = flat;
    let o = &scene.objects[obj];
    if let Some(vn) = &o.vertex_normals {
        let idx = &o.mesh.simplices[local];
        let mut s = [0.0; N];
        for k in 0..N {
            s = add_scaled(&s, hit.bary[k], &vn[idx[k] as usize]);
        }
        let l = norm(&s);
        if l > 0.0 {
            n = scale(&s, 1.0 / l);
        }
    }
    if scene.render.two_sided && dot(&flat, &ray.dir) > 0.0 {
        n = scale(&n, -1.0);
    }
    n
}

/// A light as seen from a point x.
pub(crate) struct TowardLight<'a, const N: usize> {
    /// The unit vector l̂ from x toward the light.
    pub(crate) dir: Vector<N>,
    /// The distance to the light (infinite for a directional light).
    pub(crate) dist: f64,
    /// The light's colour I_L.
    pub(crate) color: &'a Rgb,
    /// The attenuation a_L of its colour at x: 1, or r^(−falloff) at distance r.
    pub(crate) atten: f64,
}

impl<const N: usize> TowardLight<'_, N> {
    /// The same light without attenuation (its colour I_L alone).
    #[inline(always)]
    pub(crate) fn unattenuated(&self) -> Self {
        TowardLight {
            atten: 1.0,
            ..*self
        }
    }
}

/// `light` as seen from `x`; `None` when x is at a point light (no direction to it).
#[inline(always)]
pub(crate) fn toward_light<'a, const N: usize>(
    light: &'a Light<N>,
    x: &Vector<N>,
) -> Option<TowardLight<'a, N>> {
    match light {
        Light::Directional { direction, color } => Some(TowardLight {
            dir: *direction,
            dist: f64::INFINITY,
            color,
            atten: 1.0,
        }),
        Light::Point {
            position,
            color,
            falloff,
        } => {
            let d = sub(position, x);
            let dist = norm(&d);
            if !(dist > 0.0) {
                return None;
            }
            let atten = if *falloff == 0.0 {
                1.0
            } else {
                dist.powf(-falloff)
            };
            Some(TowardLight {
                dir: scale(&d, 1.0 / dist),
                dist,
                color,
                atten,
            })
        }
    }
}

/// Gouraud's factors of `light` at a vertex `x` of unit normal `n`: (a·max(0, n̂·l̂),
/// a·max(0, n̂·ĥ)^shininess) with l̂ and a the light's direction and attenuation seen from the
/// vertex and ĥ the half vector of l̂ and the direction from the vertex to the eye (0 without a
/// `specular` term); `None` when the vertex faces away from the light.
#[inline(always)]
pub(super) fn vertex_factors<const N: usize>(
    scene: &Scene<N>,
    light: &Light<N>,
    x: &Vector<N>,
    n: &Vector<N>,
    shininess: f64,
    specular: bool,
) -> Option<(f64, f64)> {
    let to_light = toward_light(light, x)?;
    let ndl = dot(n, &to_light.dir);
    if ndl <= 0.0 {
        return None;
    }
    let spec = if specular {
        let e = scene.camera.toward_eye(x);
        let len = norm(&e);
        let v = if len > 0.0 { scale(&e, 1.0 / len) } else { *n };
        to_light.atten * blinn_phong(n, &to_light.dir, &v, shininess)
    } else {
        0.0
    };
    Some((to_light.atten * ndl, spec))
}

/// The shadow ray from a hit point `x` on a simplex of unit normal `flat` toward a light in
/// direction `l` at distance `dist`, and its largest t: it starts `eps` off the simplex's
/// hyperplane on the light's side (`along`: l̂·n̂ ≥ 0) and ends `eps` before the light.
#[inline(always)]
pub(super) fn shadow_ray<const N: usize>(
    x: &Vector<N>,
    flat: &Vector<N>,
    along: bool,
    l: &Vector<N>,
    dist: f64,
    eps: f64,
) -> (Ray<N>, f64) {
    let ray = Ray {
        origin: add_scaled(x, if along { eps } else { -eps }, flat),
        dir: *l,
    };
    (ray, dist - eps)
}

/// The Blinn–Phong specular factor max(0, n̂·ĥ)^shininess, ĥ the unit half vector of the
/// directions `l` to the light and `v` to the viewer (`l` when they are opposite).
#[inline(always)]
pub(super) fn blinn_phong<const N: usize>(
    n: &Vector<N>,
    l: &Vector<N>,
    v: &Vector<N>,
    shininess: f64,
) -> f64 {
    let s = add(l, v);
    let len = norm(&s);
    let h = if len > 0.0 { scale(&s, 1.0 / len) } else { *l };
    power(dot(n, &h).max(0.0), shininess)
}

/// Whole exponents up to this are taken by repeated squaring in [`power`].
const SQUARING_MAX: f64 = 1024.0;

/// `x^s` for the specular factor (x ∈ [0, 1], s ≥ 0): by repeated squaring when s is a whole
/// number up to [`SQUARING_MAX`] (the usual shininess: a few products instead of a call of
/// `pow`, which took 7–8 % of a shaded 4D trace), else `powf`. Each squaring at most doubles
/// the relative error, so it stays below s·2⁻⁵² ≤ 2.3·10⁻¹³ (the retina stores f32); the same
/// bits on every machine (plain products, no library call).
#[inline(always)]
pub(super) fn power(x: f64, s: f64) -> f64 {
    if !(s <= SQUARING_MAX && s.fract() == 0.0) {
        return x.powf(s);
    }
    let (mut e, mut base, mut acc) = (s as u32, x, 1.0);
    while e != 0 {
        if e & 1 == 1 {
            acc *= base;
        }
        e >>= 1;
        if e != 0 {
            base *= base;
        }
    }
    acc
}

/// One light's term a_L · I_L ∘ (`diffuse` · `ndl` + `specular` · `spec`), with `diffuse` the
/// material's k_d ∘ C, `ndl` = n̂·l̂ and `spec` the [`blinn_phong`] factor.
#[inline(always)]
pub(super) fn light_term<const N: usize>(
    light: &TowardLight<'_, N>,
    diffuse: &Rgb,
    ndl: f64,
    specular: &Rgb,
    spec: f64,
) -> Rgb {
    std::array::from_fn(|k| light.atten * light.color[k] * (diffuse[k] * ndl + specular[k] * spec))
}

/// A distinct, stable colour per global primitive id (the `primitive_id` render mode).
pub(crate) fn id_color(id: u32) -> Rgb {
    let mut h = SplitMix(id as u64);
    let v = h.next();
    std::array::from_fn(|k| 0.25 + 0.75 * (((v >> (k * 16)) & 0xffff) as f64 / 65535.0))
}

/// Near and far depth of the scene's bounding sphere, for the `depth` render mode.
pub(crate) fn depth_range<const N: usize>(scene: &Scene<N>) -> (f64, f64) {
    let mut lo = [f64::INFINITY; N];
    let mut hi = [f64::NEG_INFINITY; N];
    for o in scene.objects.iter() {
        for v in &o.mesh.vertices {
            for k in 0..N {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    if !lo[0].is_finite() {
        return (0.0, 1.0);
    }
    let centre: Vector<N> = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = 0.5 * norm(&sub(&hi, &lo));
    let view = scene.camera.axis(N - 1);
    let d = dot(&sub(&centre, &scene.camera.position), &view);
    let (near, far) = ((d - radius).max(0.0), d + radius);
    if far > near {
        (near, far)
    } else {
        (near, near + 1.0)
    }
}
