//! Mesh arrays in the description: rows of numbers (`vertices`, `simplices`, `triangles`) and
//! one number per vertex (`values`), either inline lists (TOML, dicts) or one flat, shared
//! buffer handed over by the bindings from a numpy array without a trip through lists.
//!
//! Both forms read and compare the same: an array equals the inline lists with the same
//! numbers (what it becomes on a TOML round trip), and is written as those lists.
//!
//! A buffer ([`Shared`]) is the description's own, or lent by an owner that keeps it alive and
//! unchanged: the bindings lend the memory of a numpy array whose numbers lie in a `bytes`
//! object, so that a mesh goes from the Python scene's snapshot to the build without a copy.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::borrow::Cow;
use std::sync::Arc;

/// A number kept in a mesh array, compared bit for bit (so that NaN equals itself and a copy
/// of a description equals the original).
pub trait Number: Copy + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    /// The number's bits.
    fn bits(self) -> u64;
}

impl Number for f64 {
    fn bits(self) -> u64 {
        self.to_bits()
    }
}

impl Number for i64 {
    fn bits(self) -> u64 {
        self as u64
    }
}

/// An immutable buffer of numbers, shared between copies of the description: its own (from a
/// `Vec`), or lent ([`Shared::lent`]) by an owner that keeps the memory alive and unchanged for
/// as long as it is held.
#[derive(Clone)]
pub struct Shared<T: 'static>(Arc<dyn AsRef<[T]> + Send + Sync>);

impl<T: Number> Shared<T> {
    /// The numbers of `owner`, which must not change while the buffer or a copy of it is held
    /// (`as_ref` must give the same numbers every time).
    pub fn lent(owner: impl AsRef<[T]> + Send + Sync + 'static) -> Self {
        Shared(Arc::new(owner))
    }

    /// Whether `a` and `b` are copies of one buffer.
    pub fn same(a: &Self, b: &Self) -> bool {
        std::ptr::addr_eq(Arc::as_ptr(&a.0), Arc::as_ptr(&b.0))
    }
}

impl<T: 'static> std::ops::Deref for Shared<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        (*self.0).as_ref()
    }
}

impl<T: Number> From<Vec<T>> for Shared<T> {
    fn from(v: Vec<T>) -> Self {
        Shared(Arc::new(v))
    }
}

impl<T: std::fmt::Debug + 'static> std::fmt::Debug for Shared<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// Rows of `width` numbers in one flat C-ordered buffer, shared between copies of the
/// description.
#[derive(Debug, Clone)]
pub struct Table<T: 'static> {
    width: usize,
    values: Shared<T>,
}

impl<T: Number> Table<T> {
    /// `values` as rows of `width`; `None` unless `width` divides their count (a table of no
    /// rows may have any width, a table with rows a positive one).
    pub fn new(width: usize, values: impl Into<Shared<T>>) -> Option<Table<T>> {
        let values = values.into();
        let fits = if width == 0 {
            values.is_empty()
        } else {
            values.len() % width == 0
        };
        fits.then_some(Table { width, values })
    }

    /// Numbers per row.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// All numbers, row after row.
    pub fn values(&self) -> &[T] {
        &self.values
    }
}

/// Rows of numbers: inline lists, or a [`Table`] from the bindings (never read from TOML).
#[derive(Debug, Clone)]
pub enum Rows<T: 'static> {
    /// Nested lists, as read (rows may differ in length until the scene is built).
    Inline(Vec<Vec<T>>),
    /// One flat buffer of equal rows.
    Array(Table<T>),
}

impl<T: Number> Rows<T> {
    /// Number of rows.
    pub fn len(&self) -> usize {
        match self {
            Rows::Inline(r) => r.len(),
            Rows::Array(t) => t.rows(),
        }
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The numbers row after row when every row has `width` of them (borrowed from an array);
    /// otherwise the first row that does not, and its length.
    pub fn flat(&self, width: usize) -> Result<Cow<'_, [T]>, (usize, usize)> {
        match self {
            Rows::Array(t) if t.width == width || t.values.is_empty() => {
                Ok(Cow::Borrowed(t.values()))
            }
            Rows::Array(t) => Err((0, t.width)),
            Rows::Inline(r) => match r.iter().position(|row| row.len() != width) {
                Some(i) => Err((i, r[i].len())),
                None => Ok(Cow::Owned(r.iter().flatten().copied().collect())),
            },
        }
    }

    /// Row `i`.
    fn row(&self, i: usize) -> &[T] {
        match self {
            Rows::Inline(r) => &r[i],
            Rows::Array(t) => &t.values[i * t.width..(i + 1) * t.width],
        }
    }
}

impl<T: Number> PartialEq for Rows<T> {
    fn eq(&self, other: &Self) -> bool {
        let same = |a: &[T], b: &[T]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.bits() == y.bits())
        };
        match (self, other) {
            (Rows::Array(a), Rows::Array(b)) if Shared::same(&a.values, &b.values) => {
                a.width == b.width
            }
            _ => {
                self.len() == other.len()
                    && (0..self.len()).all(|i| same(self.row(i), other.row(i)))
            }
        }
    }
}

/// Written as the nested lists inline rows are read from.
impl<T: Number + Serialize> Serialize for Rows<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq((0..self.len()).map(|i| self.row(i)))
    }
}

/// Read as nested lists (the errors are those of `Vec<Vec<T>>`, located by the loader).
impl<'de, T: Number + Deserialize<'de>> Deserialize<'de> for Rows<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Vec::<Vec<T>>::deserialize(d).map(Rows::Inline)
    }
}

/// One number per vertex: an inline list, or a shared buffer from the bindings.
#[derive(Debug, Clone)]
pub enum Column<T: 'static> {
    /// A list, as read.
    Inline(Vec<T>),
    /// A flat buffer from a 1-D array.
    Array(Shared<T>),
}

impl<T: Number> Column<T> {
    /// The numbers.
    pub fn values(&self) -> &[T] {
        match self {
            Column::Inline(v) => v,
            Column::Array(a) => a,
        }
    }
}

impl<T: Number> PartialEq for Column<T> {
    fn eq(&self, other: &Self) -> bool {
        let (a, b) = (self.values(), other.values());
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.bits() == y.bits())
    }
}

impl<T: Number + Serialize> Serialize for Column<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.values().serialize(s)
    }
}

impl<'de, T: Number + Deserialize<'de>> Deserialize<'de> for Column<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Vec::<T>::deserialize(d).map(Column::Inline)
    }
}

#[cfg(test)]
mod tests;
