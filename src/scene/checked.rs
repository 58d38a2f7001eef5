//! Number types that validate while they deserialize, so a bad value in a scene file is
//! reported at its own line and column.

use serde::{Deserialize, Deserializer, Serialize};

macro_rules! checked_f32 {
    ($name:ident, $doc:literal, $ok:expr, $msg:literal) => {
        #[doc = $doc]
        #[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Serialize)]
        #[serde(transparent)]
        pub struct $name(pub f32);

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = f64::deserialize(d)?;
                let f = v as f32;
                let ok: fn(f32) -> bool = $ok;
                if ok(f) {
                    Ok($name(f))
                } else {
                    Err(serde::de::Error::custom(format!(concat!("{} is out of range: ", $msg), v)))
                }
            }
        }
    };
}

checked_f32!(
    Positive,
    "A finite number greater than zero.",
    |f| f.is_finite() && f > 0.0,
    "must be a finite number greater than zero"
);
checked_f32!(
    NonNegative,
    "A finite number, zero or greater.",
    |f| f.is_finite() && f >= 0.0,
    "must be a finite number, zero or greater"
);
checked_f32!(
    Fraction,
    "A number from 0 to 1.",
    |f| f.is_finite() && (0.0..=1.0).contains(&f),
    "must be a number from 0 to 1"
);
checked_f32!(Finite, "A finite number.", |f| f.is_finite(), "must be a finite number");
checked_f32!(
    Travel,
    "A self-collision travel bound: above 0, at most 2 (`MAX_TRAVEL`).",
    |f| f > 0.0 && f <= crate::model::self_collision::MAX_TRAVEL,
    "must be above 0 and at most 2"
);

/// A 3-vector of finite numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Vec3(pub [f32; 3]);

impl<'de> Deserialize<'de> for Vec3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = <[f64; 3]>::deserialize(d)?;
        let f = v.map(|c| c as f32);
        if f.iter().all(|c| c.is_finite()) {
            Ok(Vec3(f))
        } else {
            Err(serde::de::Error::custom(format!(
                "{v:?} is out of range: every component must be a finite number"
            )))
        }
    }
}

/// A count of at least one, at most `u32::MAX`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Count(pub u32);

impl<'de> Deserialize<'de> for Count {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if v >= 1 && v <= u32::MAX as i64 {
            Ok(Count(v as u32))
        } else {
            Err(serde::de::Error::custom(format!(
                "{v} is out of range: must be a whole number of at least 1"
            )))
        }
    }
}

checked_f32!(
    Degrees180,
    "An angle in degrees between 0 and 180 inclusive.",
    |f| f.is_finite() && (0.0..=180.0).contains(&f),
    "must be an angle between 0 and 180 degrees"
);
