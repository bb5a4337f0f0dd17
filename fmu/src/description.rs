//! The FMU's modelDescription.xml (FMI 2.0 Co-Simulation), written from the variable
//! table ([`crate::variables::VARIABLES`]) and the start values, and its GUID: a hash
//! of the description's own text, so that two FMUs of different start values differ
//! and the same options give the same file.

use crate::variables::{value_reference, Kind, Role, Start, VARIABLES};
use core::fmt::Write as _;

/// The FMU's model identifier: the name of its binary
/// (`binaries/linux64/structomat_ccc.so`).
pub const MODEL_IDENTIFIER: &str = "structomat_ccc";

/// The log categories the FMU declares (`fmi2SetDebugLogging` takes these names).
pub const LOG_CATEGORIES: [(&str, &str); 3] = [
    ("logStatusError", "a call that returns fmi2Error, and why"),
    (
        "logStatusWarning",
        "a call that returns fmi2Warning, and why",
    ),
    (
        "logEvents",
        "the diode's mode changes (with debug logging on)",
    ),
];

/// The units: name and SI base-unit exponents (kg, m, s, rad) and a degree's factor.
const UNITS: [(&str, &str); 11] = [
    ("s", r#"s="1""#),
    ("m", r#"m="1""#),
    ("kg", r#"kg="1""#),
    ("kg.m2", r#"kg="1" m="2""#),
    ("m/s2", r#"m="1" s="-2""#),
    ("rad", r#"rad="1""#),
    ("deg", r#"rad="1" factor="0.017453292519943295""#),
    ("rad/s", r#"rad="1" s="-1""#),
    ("N.m", r#"kg="1" m="2" s="-2""#),
    ("N.m.s/rad", r#"kg="1" m="2" s="-1" rad="-1""#),
    ("J", r#"kg="1" m="2" s="-2""#),
];

/// What the FMU is built for: its start values, and the default experiment's stop
/// time (s; its step is the start value of h).
#[derive(Clone, Debug, PartialEq)]
pub struct Description {
    /// The parameters' and inputs' start values.
    pub start: Start,
    /// The default experiment's stop time, s.
    pub stop_time: f64,
    /// The model's description line (the scenario's).
    pub text: String,
}

impl Default for Description {
    /// The defaults of [`Start`], 1 s.
    fn default() -> Self {
        Description {
            start: Start::default(),
            stop_time: 1.0,
            text: "SPEC 3's reference converter, S2's inputs".to_string(),
        }
    }
}

impl Description {
    /// The modelDescription.xml and its GUID.
    pub fn xml(&self) -> (String, String) {
        let body = self.body();
        let guid = guid_of(&body);
        (body.replace(GUID_PLACE, &guid), guid)
    }

    /// The GUID alone.
    pub fn guid(&self) -> String {
        guid_of(&self.body())
    }

    /// The XML with [`GUID_PLACE`] where the GUID goes.
    fn body(&self) -> String {
        let mut x = String::new();
        let h = self.start.reals[crate::variables::vr::H as usize];
        let _ = write!(
            x,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
             <fmiModelDescription fmiVersion=\"2.0\" modelName=\"structomat converter twin\" \
             guid=\"{GUID_PLACE}\" description=\"{}\" generationTool=\"structomat-fmu {}\" \
             variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">\n",
            escape(&format!(
                "The Constantinesco torque converter's digital twin (structomat::ccc::Twin): {}",
                self.text
            )),
            env!("CARGO_PKG_VERSION"),
        );
        let _ = writeln!(
            x,
            "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" needsExecutionTool=\"false\" \
             canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\" \
             maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" \
             canBeInstantiatedOnlyOncePerProcess=\"false\" \
             canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"true\" \
             canSerializeFMUstate=\"false\" providesDirectionalDerivative=\"false\"/>"
        );
        x.push_str("  <UnitDefinitions>\n");
        for (name, base) in UNITS {
            let _ = writeln!(
                x,
                "    <Unit name=\"{}\"><BaseUnit {base}/></Unit>",
                escape(name)
            );
        }
        x.push_str("  </UnitDefinitions>\n  <LogCategories>\n");
        for (name, what) in LOG_CATEGORIES {
            let _ = writeln!(
                x,
                "    <Category name=\"{name}\" description=\"{}\"/>",
                escape(what)
            );
        }
        let _ = writeln!(
            x,
            "  </LogCategories>\n  <DefaultExperiment startTime=\"0\" stopTime=\"{}\" stepSize=\"{}\"/>\n  <ModelVariables>",
            self.stop_time, h
        );
        let mut outputs = Vec::new();
        for (k, v) in VARIABLES.iter().enumerate() {
            let _ = writeln!(x, "    <!-- index {} -->", k + 1);
            let (causality, variability, initial) = match (v.role, v.kind) {
                (Role::Parameter, _) => ("parameter", "fixed", " initial=\"exact\""),
                (Role::Input, _) => ("input", "continuous", ""),
                (Role::Output, Kind::Real) => ("output", "continuous", " initial=\"calculated\""),
                (Role::Output, _) => ("output", "discrete", " initial=\"calculated\""),
            };
            if v.role == Role::Output {
                outputs.push(k + 1);
            }
            let _ = writeln!(
                x,
                "    <ScalarVariable name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{causality}\" variability=\"{variability}\"{initial}>",
                escape(v.name),
                value_reference(k),
                escape(v.description)
            );
            let tag = match v.kind {
                Kind::Real => "Real",
                Kind::Integer => "Integer",
                Kind::Boolean => "Boolean",
            };
            let unit = if v.unit.is_empty() {
                String::new()
            } else {
                format!(" unit=\"{}\"", escape(v.unit))
            };
            let start = self
                .start
                .text(k)
                .map_or_else(String::new, |s| format!(" start=\"{s}\""));
            let _ = writeln!(x, "      <{tag}{unit}{start}/>\n    </ScalarVariable>");
        }
        x.push_str("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
        for i in &outputs {
            let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
        }
        x.push_str("    </Outputs>\n    <InitialUnknowns>\n");
        for i in &outputs {
            let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
        }
        x.push_str("    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
        x
    }
}

/// Where the GUID goes in the description's text before it is known.
const GUID_PLACE: &str = "@GUID@";

/// A GUID-shaped hash of `text`: FNV-1a over 128 bits, as `{8-4-4-4-12}` hex digits.
/// Not a random UUID: the same description has the same GUID.
pub fn guid_of(text: &str) -> String {
    const OFFSET: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    const PRIME: u128 = 0x0000_0000_0100_0000_0000_0000_0000_013b;
    let h = text
        .bytes()
        .fold(OFFSET, |h, b| (h ^ u128::from(b)).wrapping_mul(PRIME));
    let d = format!("{h:032x}");
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &d[0..8],
        &d[8..12],
        &d[12..16],
        &d[16..20],
        &d[20..32]
    )
}

/// `s` with XML's five special characters escaped.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

#[cfg(test)]
mod tests {
    use super::*;

    // The GUID follows the start values; the description names every variable once.
    #[test]
    fn guid_follows_the_start_values() {
        let d = Description::default();
        let (xml, guid) = d.xml();
        assert!(xml.contains(&format!("guid=\"{guid}\"")));
        assert_eq!(d.guid(), guid);
        let mut other = d.clone();
        other.start.reals[crate::variables::vr::LOAD as usize] = 0.0;
        assert_ne!(other.guid(), guid);
        for v in VARIABLES.iter() {
            assert_eq!(
                xml.matches(&format!("name=\"{}\"", v.name)).count(),
                1,
                "{}",
                v.name
            );
        }
        assert!(xml.contains("stepSize=\"0.0001\""));
    }

    // Every variable's unit is one the UnitDefinitions define (an importer refuses a
    // description whose variable names an undefined unit).
    #[test]
    fn every_unit_is_defined() {
        for v in crate::variables::VARIABLES
            .iter()
            .filter(|v| !v.unit.is_empty())
        {
            assert!(
                UNITS.iter().any(|(u, _)| *u == v.unit),
                "{}: {}",
                v.name,
                v.unit
            );
        }
    }
}
