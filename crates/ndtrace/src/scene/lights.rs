//! Lights: a `[[lights]]` entry checked and made ready for shading (course notes, Part II(B)
//! "4D Shading": directional and point lights in R^N).

use super::desc::LightDesc;
use super::errors::PathError;
use super::fields::{rgb, vec_n, R};
use crate::linalg::{norm, scale, Rgb, Vector};

/// A light ready for shading.
#[derive(Debug, Clone, PartialEq)]
pub enum Light<const N: usize> {
    /// Unit direction toward the light.
    Directional { direction: Vector<N>, color: Rgb },
    /// Position, colour and falloff exponent.
    Point {
        position: Vector<N>,
        color: Rgb,
        falloff: f64,
    },
}

/// The light a `[[lights]]` entry describes, checked (`path` locates errors).
pub(super) fn light<const N: usize>(l: &LightDesc, path: &str) -> R<Light<N>> {
    Ok(match l {
        LightDesc::Directional { direction, color } => {
            let d = vec_n::<N>(direction, &format!("{path}.direction"))?;
            let len = norm(&d);
            if !(len > 0.0) {
                return Err(PathError::new(
                    format!("{path}.direction"),
                    "must not be the zero vector",
                ));
            }
            Light::Directional {
                direction: scale(&d, 1.0 / len),
                color: rgb(color, &format!("{path}.color"))?,
            }
        }
        LightDesc::Point {
            position,
            color,
            falloff,
        } => {
            let f = falloff.unwrap_or(0.0);
            if !(f >= 0.0 && f.is_finite()) {
                return Err(PathError::new(
                    format!("{path}.falloff"),
                    format!("must be a finite number ≥ 0, got {f}"),
                ));
            }
            Light::Point {
                position: vec_n::<N>(position, &format!("{path}.position"))?,
                color: rgb(color, &format!("{path}.color"))?,
                falloff: f,
            }
        }
    })
}
