//! The last gate before an FMU is written: every number it carries is finite. serde_json writes
//! a NaN of the report as `null` without a word, and a NaN in the reduced body makes every
//! output of the FMU NaN in the user's simulator, far from the input that caused it. Here the
//! report is walked field by field (a serde serializer that only looks at numbers), the reduced
//! body array by array, and a few Co-Simulation steps of the runtime itself are taken at rest
//! and under unit flange loads; the first non-finite value is named with the inputs that drive it.

use crate::error::{BuildError, Result};
use fmi2::Model;
use fmu_runtime::fmu::BodyFmu;
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::ReducedBody;
use serde::Serialize;
use serde::ser::{self, Impossible};
use std::fmt;

/// What to check when a number is not finite: the inputs every reduced quantity depends on.
const LIKELY_CAUSES: &str = "the material (material.E, nu, rho), the damping (damping.alpha, beta, modal ratios), \
     the mesh's proportions and the reduction settings (reduction.*) drive it; check them for extreme values";

/// The path of the first non-finite number in `value`, serialised field by field.
pub fn first_non_finite<T: Serialize>(value: &T) -> Option<String> {
    let mut walk = Walk { path: String::new(), found: None };
    // our serializer never fails but by finding: a found path is the answer
    let _ = value.serialize(&mut walk);
    walk.found
}

/// Refuses a report with a non-finite number, naming its field.
pub fn check_report<T: Serialize>(report: &T) -> Result<()> {
    match first_non_finite(report) {
        None => Ok(()),
        Some(path) => Err(BuildError::not_finite(format!(
            "the report's {path} is not a finite number (NaN or infinite): {LIKELY_CAUSES}"
        ))),
    }
}

/// Refuses a reduced body with a non-finite array entry (the FMU's resources), naming the array.
/// Every array the FMU's file carries is checked: they are read from the very container that is
/// written, so an array added to the file cannot be missed here.
pub fn check_reduced(body: &ReducedBody) -> Result<()> {
    let container = body.to_container();
    for (key, values) in container.arrays() {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(BuildError::not_finite(format!(
                "the reduced body's {} has a non-finite entry ({} at index {i}): {LIKELY_CAUSES}",
                array_words(body, key),
                values[i]
            )));
        }
    }
    // the cutoff may be infinite (every mode dynamic), never NaN
    if body.dynamic_cutoff.is_nan() {
        return Err(BuildError::not_finite(format!(
            "the dynamic cutoff is NaN: check reduction.dynamic_cutoff; {LIKELY_CAUSES}"
        )));
    }
    Ok(())
}

/// The array `key` of the reduced-body file in the words of the model.
fn array_words(body: &ReducedBody, key: &str) -> String {
    let named = |list: &str, i: &str| -> Option<String> {
        let i: usize = i.parse().ok()?;
        match list {
            "flange" => body.flanges.get(i).map(|f| format!("flange \"{}\"", f.name)),
            _ => body.stress_points.get(i).map(|p| format!("stress point \"{}\"", p.name)),
        }
    };
    let parts: Vec<&str> = key.split('.').collect();
    match parts.as_slice() {
        ["omega"] => "omega (modal frequencies)".to_string(),
        ["damping", "modal"] => "modal damping".to_string(),
        ["damping", which] => format!("damping {which}"),
        ["first_moment"] => "first moment of mass".to_string(),
        ["c_t"] => "C_t (translational coupling)".to_string(),
        ["c_r"] => "C_r (rotational coupling)".to_string(),
        ["rotation", "G"] => "G_a (gyroscopic terms)".to_string(),
        ["rotation", "O"] => "O_ab".to_string(),
        ["rotation", "o"] => "o_ab".to_string(),
        ["stiffening", "flange", i] => {
            format!("geometric stiffening of flange load {}", i.parse::<usize>().map_or(0, |i| i + 1))
        }
        ["stiffening", case] => format!("geometric stiffening ({case})"),
        [list @ ("flange" | "stress"), i, "position"] => {
            named(list, i).map_or(key.to_string(), |n| format!("{n} reference point"))
        }
        ["flange", i, "shapes"] => named("flange", i).map_or(key.to_string(), |n| format!("{n} shapes")),
        ["stress", i, "modes"] => named("stress", i).map_or(key.to_string(), |n| format!("{n} stress modes")),
        _ => key.replace('_', " "),
    }
}

/// A few Co-Simulation steps of the FMU's own equations: at rest, then with a unit force and
/// torque on every force flange (and unit gravity); every output must stay finite. Cheap (the
/// reduced body has at most a thousand modes), and it runs the very code the FMU ships.
pub fn smoke_step(body: &ReducedBody) -> Result<()> {
    let table = VariableTable::new(body);
    let outputs: Vec<(u32, &str)> = table
        .variables
        .iter()
        .filter(|v| v.name.contains('.') || v.name.starts_with('q'))
        .map(|v| (v.vr, v.name.as_str()))
        .collect();
    let mut fmu = BodyFmu::from_reduced(body.clone());
    let failed = |what: &str, e: fmi2::ModelError| {
        BuildError::not_finite(format!("the FMU's first steps fail ({what}): {e}; {LIKELY_CAUSES}")).caused_by(e)
    };
    fmu.enter_initialization(0.0).map_err(|e| failed("initialisation", e))?;
    fmu.exit_initialization().map_err(|e| failed("initialisation", e))?;
    let h = 1e-3;
    let mut t = 0.0;
    for phase in ["at rest", "under unit flange loads and gravity"] {
        if phase != "at rest" {
            for f in &body.flanges {
                for q in ["f", "t"] {
                    for i in 1..=3 {
                        if let Some(vr) = table.value_reference(&format!("{}.{q}[{i}]", f.name)) {
                            fmu.set_real(vr, 1.0).map_err(|e| failed("setting a flange load", e))?;
                        }
                    }
                }
            }
            if let Some(vr) = table.value_reference("g[3]") {
                // a parameter: the runtime may refuse it after initialisation, which is fine
                let _ = fmu.set_real(vr, -1.0);
            }
        }
        for _ in 0..5 {
            fmu.do_step(t, h).map_err(|e| failed(phase, e))?;
            t += h;
        }
        for &(vr, name) in &outputs {
            let v = fmu.get_real(vr).map_err(|e| failed(phase, e))?;
            if !v.is_finite() {
                return Err(BuildError::not_finite(format!(
                    "the FMU's output {name} is {v} after 5 steps of 1 ms {phase}: {LIKELY_CAUSES}"
                )));
            }
        }
    }
    Ok(())
}

/// A serializer that serialises nothing: it walks the value, keeping the path, until it meets a
/// non-finite float.
struct Walk {
    path: String,
    found: Option<String>,
}

#[derive(Debug)]
struct Found;

impl fmt::Display for Found {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("found a non-finite number")
    }
}
impl std::error::Error for Found {}
impl ser::Error for Found {
    fn custom<T: fmt::Display>(_: T) -> Self {
        Found
    }
}

type R = std::result::Result<(), Found>;

impl Walk {
    fn number(&mut self, v: f64) -> R {
        if v.is_finite() {
            return Ok(());
        }
        self.found = Some(if self.path.is_empty() { "value".into() } else { self.path.clone() });
        Err(Found)
    }
    fn at<T: Serialize + ?Sized>(&mut self, segment: &str, value: &T) -> R {
        let len = self.path.len();
        self.path.push_str(segment);
        let r = value.serialize(&mut *self);
        self.path.truncate(len);
        r
    }
}

impl<'a> ser::Serializer for &'a mut Walk {
    type Ok = ();
    type Error = Found;
    type SerializeSeq = Seq<'a>;
    type SerializeTuple = Seq<'a>;
    type SerializeTupleStruct = Seq<'a>;
    type SerializeTupleVariant = Seq<'a>;
    type SerializeMap = Impossible<(), Found>;
    type SerializeStruct = Seq<'a>;
    type SerializeStructVariant = Seq<'a>;

    fn serialize_bool(self, _: bool) -> R {
        Ok(())
    }
    fn serialize_i8(self, _: i8) -> R {
        Ok(())
    }
    fn serialize_i16(self, _: i16) -> R {
        Ok(())
    }
    fn serialize_i32(self, _: i32) -> R {
        Ok(())
    }
    fn serialize_i64(self, _: i64) -> R {
        Ok(())
    }
    fn serialize_u8(self, _: u8) -> R {
        Ok(())
    }
    fn serialize_u16(self, _: u16) -> R {
        Ok(())
    }
    fn serialize_u32(self, _: u32) -> R {
        Ok(())
    }
    fn serialize_u64(self, _: u64) -> R {
        Ok(())
    }
    fn serialize_f32(self, v: f32) -> R {
        self.number(f64::from(v))
    }
    fn serialize_f64(self, v: f64) -> R {
        self.number(v)
    }
    fn serialize_char(self, _: char) -> R {
        Ok(())
    }
    fn serialize_str(self, _: &str) -> R {
        Ok(())
    }
    fn serialize_bytes(self, _: &[u8]) -> R {
        Ok(())
    }
    fn serialize_none(self) -> R {
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> R {
        v.serialize(self)
    }
    fn serialize_unit(self) -> R {
        Ok(())
    }
    fn serialize_unit_struct(self, _: &'static str) -> R {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> R {
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> R {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(self, _: &'static str, _: u32, _: &'static str, v: &T) -> R {
        v.serialize(self)
    }
    fn serialize_seq(self, _: Option<usize>) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
    fn serialize_tuple(self, _: usize) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
    fn serialize_map(self, _: Option<usize>) -> std::result::Result<Impossible<(), Found>, Found> {
        // the report has no maps; were one added, its numbers would go unchecked: fail loudly
        Err(Found)
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> std::result::Result<Seq<'a>, Found> {
        Ok(Seq { walk: self, index: 0 })
    }
}

/// The elements or fields of one compound value.
struct Seq<'a> {
    walk: &'a mut Walk,
    index: usize,
}

impl Seq<'_> {
    fn element<T: Serialize + ?Sized>(&mut self, v: &T) -> R {
        let r = self.walk.at(&format!("[{}]", self.index), v);
        self.index += 1;
        r
    }
    fn field<T: Serialize + ?Sized>(&mut self, key: &'static str, v: &T) -> R {
        let segment = if self.walk.path.is_empty() { key.to_string() } else { format!(".{key}") };
        self.walk.at(&segment, v)
    }
}

/// serde's six compound traits, each forwarding to `Seq::element` (positional) or `Seq::field`
/// (named): the walk treats a tuple like a sequence and a variant like its struct.
macro_rules! compound {
    ($($trait:ident :: $method:ident $(($key:ident))?),* $(,)?) => {$(
        impl ser::$trait for Seq<'_> {
            type Ok = ();
            type Error = Found;
            fn $method<T: Serialize + ?Sized>(&mut self, $($key: &'static str,)? v: &T) -> R {
                compound!(@forward self, v $(, $key)?)
            }
            fn end(self) -> R {
                Ok(())
            }
        }
    )*};
    (@forward $self:ident, $v:ident) => { $self.element($v) };
    (@forward $self:ident, $v:ident, $key:ident) => { $self.field($key, $v) };
}

compound!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field,
    SerializeStruct::serialize_field(key),
    SerializeStructVariant::serialize_field(key),
);

#[cfg(test)]
mod tests {
    use super::*;
    use fmu_runtime::reduced::two_mode_body;

    #[derive(Serialize)]
    struct Inner {
        values: Vec<f64>,
        name: String,
    }
    #[derive(Serialize)]
    struct Outer {
        mass: f64,
        none: Option<f64>,
        inner: Vec<Inner>,
    }

    #[test]
    fn the_first_non_finite_number_is_named_by_its_path() {
        let mut v = Outer {
            mass: 1.0,
            none: None,
            inner: vec![
                Inner { values: vec![1.0], name: "a".into() },
                Inner { values: vec![2.0, 3.0], name: "b".into() },
            ],
        };
        assert_eq!(first_non_finite(&v), None);
        v.inner[1].values[1] = f64::NAN;
        assert_eq!(first_non_finite(&v).as_deref(), Some("inner[1].values[1]"));
        v.mass = f64::INFINITY;
        let e = check_report(&v).unwrap_err().to_string();
        assert!(e.contains("mass") && e.contains("material.E"), "{e}");
    }

    #[test]
    fn a_reduced_body_with_a_nan_is_refused_and_a_good_one_steps() {
        let good = two_mode_body();
        check_reduced(&good).unwrap();
        smoke_step(&good).unwrap();
        let mut bad = two_mode_body();
        bad.flanges[0].shapes[3] = f64::NAN;
        let e = check_reduced(&bad).unwrap_err().to_string();
        assert!(e.contains("flange \"tip\" shapes") && e.contains("index 3"), "{e}");
        let mut bad = two_mode_body();
        bad.omega[1] = f64::INFINITY;
        assert!(check_reduced(&bad).unwrap_err().to_string().contains("omega"));
        // every array the file carries is checked, the stress points' too
        let mut bad = two_mode_body();
        let n = bad.n_modes();
        let point = fmu_runtime::reduced::StressPoint {
            name: "stress.n7".into(),
            description: "node 7".into(),
            position: [0.5, 0.0, 0.0],
            modes: vec![0.0; 6 * n],
        };
        bad.stress_points.push(point.clone());
        check_reduced(&bad).unwrap();
        bad.stress_points[0].modes[6 * n - 1] = f64::NAN;
        let e = check_reduced(&bad).unwrap_err().to_string();
        assert!(e.contains("stress point \"stress.n7\" stress modes"), "{e}");
        bad.stress_points[0] = point;
        bad.stress_points[0].position[2] = f64::NEG_INFINITY;
        let e = check_reduced(&bad).unwrap_err().to_string();
        assert!(e.contains("stress point \"stress.n7\" reference point"), "{e}");
    }
}
