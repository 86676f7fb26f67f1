use super::*;
use crate::camera::Projection;
use crate::composite::CompositeMode;
use crate::scene::desc::RenderMode;
use serde::de::value::{Error, StrDeserializer};
use serde::de::IntoDeserializer;

/// Every captured name deserializes, to distinct variants, and nothing else does.
fn accepted<T: DeserializeOwned + PartialEq + fmt::Debug>(names: &[&str]) {
    assert_eq!(variants::<T>(), names);
    let parse = |n: &str| T::deserialize::<StrDeserializer<'_, Error>>(n.into_deserializer());
    let parsed: Vec<T> = names.iter().map(|n| parse(n).unwrap()).collect();
    for (i, a) in parsed.iter().enumerate() {
        assert!(parsed[i + 1..].iter().all(|b| a != b), "{names:?}");
    }
    assert!(parse("no_such_name").is_err());
}

#[test]
fn variants_are_the_names_serde_accepts() {
    accepted::<CompositeMode>(&["volume", "mip", "first_hit", "slices", "illustrative"]);
    accepted::<Projection>(&["perspective", "orthographic"]);
    accepted::<RenderMode>(&["shaded", "depth", "normal", "primitive_id", "barycentric"]);
    assert!(variants::<f64>().is_empty());
    assert!(variants::<crate::composite::CompositeOptions>().is_empty());
}
