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
//! (`crate::render::shade_hit`) with these means in place of n̂·l̂ and max(0, n̂·ĥ)^s; these are
//! the colours the thickened surface's cells average to as the radius shrinks (tested against
//! traced thickenings).

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
        // x⁰ = 1 even where n·ĥ ≤ 0, as for meshes (`crate::render::shade_hit`).
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
