//! Value types of scene files that TOML has no direct form for: 3-vectors written as
//! `"x,y,z"` (or `[x, y, z]`, or a single number for the y component) and pin sets.

use glam::DVec3;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

/// A 3-vector: `"x,y,z"`, `[x, y, z]`, or a number `y` meaning `(0, y, 0)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vector(pub DVec3);

impl Serialize for Vector {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        [self.0.x, self.0.y, self.0.z].serialize(s)
    }
}

impl<'de> Deserialize<'de> for Vector {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vector;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a vector \"x,y,z\", [x, y, z], or a number for y")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Vector, E> {
                let parts: Vec<&str> = s.split(',').map(str::trim).collect();
                let numbers: Result<Vec<f64>, _> = parts.iter().map(|p| p.parse::<f64>()).collect();
                match numbers {
                    Ok(n) if n.len() == 3 => Ok(Vector(DVec3::new(n[0], n[1], n[2]))),
                    Ok(n) if n.len() == 1 => Ok(Vector(DVec3::new(0.0, n[0], 0.0))),
                    _ => Err(E::custom(format!(
                        "`{}` is not a vector: write \"x,y,z\" in numbers",
                        crate::limits::echo(s)
                    ))),
                }
            }
            fn visit_f64<E: de::Error>(self, y: f64) -> Result<Vector, E> {
                Ok(Vector(DVec3::new(0.0, y, 0.0)))
            }
            fn visit_i64<E: de::Error>(self, y: i64) -> Result<Vector, E> {
                self.visit_f64(y as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vector, A::Error> {
                let mut n = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    n.push(x);
                }
                if n.len() != 3 {
                    return Err(de::Error::custom(format!(
                        "a vector needs 3 numbers, got {}",
                        n.len()
                    )));
                }
                Ok(Vector(DVec3::new(n[0], n[1], n[2])))
            }
        }
        d.deserialize_any(V)
    }
}

/// Which particles are pinned.
#[derive(Clone, Debug, PartialEq)]
pub enum Pins {
    /// A named set.
    Preset(PinPreset),
    /// Explicit particle indices.
    Indices(Vec<usize>),
}

/// Named pin sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PinPreset {
    /// The four corners of a grid.
    Corners,
    /// The two top corners of a grid.
    TopCorners,
    /// The whole top row.
    TopEdge,
    /// The whole left column.
    LeftEdge,
    /// Every fourth particle of the left column, from the top (seed 001's cloth).
    LeftEdgeEveryFourth,
    /// The first particle (chain, rope, spring).
    First,
    /// Nothing pinned.
    None,
}

impl PinPreset {
    /// Every preset with its name.
    pub const ALL: [(&'static str, PinPreset); 7] = [
        ("corners", Self::Corners),
        ("top-corners", Self::TopCorners),
        ("top-edge", Self::TopEdge),
        ("left-edge", Self::LeftEdge),
        ("left-edge-every-4th", Self::LeftEdgeEveryFourth),
        ("first", Self::First),
        ("none", Self::None),
    ];

    /// The preset's name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, p)| *p == self)
            .map_or("none", |(n, _)| n)
    }
}

impl Serialize for Pins {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Pins::Preset(p) => s.serialize_str(p.name()),
            Pins::Indices(i) => i.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Pins {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Pins;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("one of corners, top-corners, top-edge, left-edge, first, none, or a list of particle indices")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Pins, E> {
                // `--set pins=[18446744073709551615]`: a list TOML cannot hold as
                // integers arrives as text; read it here so that resolving can say
                // which index is out of range.
                if let Some(list) = s.trim().strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
                    return list
                        .split(',')
                        .map(str::trim)
                        .filter(|i| !i.is_empty())
                        .map(|i| {
                            i.parse::<usize>().map_err(|_| {
                                E::custom(format!(
                                    "pin index `{}` is not a particle index: indices are whole numbers from 0 to one less than the number of particles",
                                    crate::limits::echo(i)
                                ))
                            })
                        })
                        .collect::<Result<Vec<_>, E>>()
                        .map(Pins::Indices);
                }
                PinPreset::ALL
                    .iter()
                    .find(|(name, _)| *name == s)
                    .map(|(_, p)| Pins::Preset(*p))
                    .ok_or_else(|| E::custom(format!("unknown pin set `{}`: expected one of corners, top-corners, top-edge, left-edge, first, none, or a list of indices", crate::limits::echo(s))))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pins, A::Error> {
                let mut indices = Vec::new();
                while let Some(i) = seq.next_element::<usize>()? {
                    indices.push(i);
                }
                Ok(Pins::Indices(indices))
            }
        }
        d.deserialize_any(V)
    }
}

/// The random seed (`seed`): any whole number from 0 to 2^64 - 1. TOML integers
/// stop at 2^63 - 1, so larger seeds are written (and may be given) as text.
pub mod seed {
    use serde::de::{self, Deserializer, Visitor};
    use serde::ser::Serializer;

    const EXPECTED: &str = "a whole number from 0 to 18446744073709551615";

    /// Writes a seed: an integer where TOML can hold it, else text.
    pub fn serialize<S: Serializer>(seed: &Option<u64>, s: S) -> Result<S::Ok, S::Error> {
        match *seed {
            Some(n) => match i64::try_from(n) {
                Ok(i) => s.serialize_some(&i),
                Err(_) => s.serialize_some(&n.to_string()),
            },
            None => s.serialize_none(),
        }
    }

    /// Reads a seed from an integer or from text holding one.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = u64;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(EXPECTED)
            }
            fn visit_i64<E: de::Error>(self, n: i64) -> Result<u64, E> {
                u64::try_from(n).map_err(|_| {
                    E::custom(format!("seed = {n} is out of range: must be {EXPECTED}"))
                })
            }
            fn visit_u64<E: de::Error>(self, n: u64) -> Result<u64, E> {
                Ok(n)
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<u64, E> {
                s.trim().parse().map_err(|_| {
                    E::custom(format!(
                        "seed = `{}` is not a seed: must be {EXPECTED}",
                        crate::limits::echo(s)
                    ))
                })
            }
        }
        d.deserialize_any(V).map(Some)
    }
}
