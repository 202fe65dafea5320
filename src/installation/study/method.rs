//! A method of the installation study as its rows name it: a model (the label of the
//! spec's [`Model`](crate::installation::study::spec::Model), such as "installation
//! lever+offset" or "DCNet trained on the vehicle", or no calibration) and its variant:
//! calibrated on one trajectory or jointly over every other, and scored with the
//! calibration's clock carried or with each scored trajectory's clock re-found from its
//! first w seconds. A method becomes its label in one place (`Display`: `"<model>"`,
//! `"<model>, joint"`, `"<model>, clock re-found in <w> s"`, `"<model>, joint, clock
//! re-found in <w> s"`), the text the tables, figures and reports hold, and is read back from a
//! label in one (`FromStr`, and [`Method::parse`] on it). In: a model's label, or a
//! row's method. Out: a [`Method`], and its label.

use std::convert::Infallible;
use std::fmt;
use std::str::FromStr;

/// What a label says after its model when the method is a joint fit.
const JOINT: &str = ", joint";

/// What a label says after its model (and its joint fit) when the clock is re-found,
/// before the seconds that found it.
const CLOCK_REFOUND: &str = ", clock re-found in ";

/// What a label says after the seconds that re-found the clock.
const SECONDS: &str = " s";

/// A method of the study: its model and its variant.
#[derive(Debug, Clone, PartialEq)]
pub struct Method {
    /// The model's label; it never ends with the words of a variant.
    pub model: String,
    pub variant: Variant,
}

/// How a model's terms are calibrated and with which clock they are scored.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Variant {
    pub fit: Fit,
    pub clock: Clock,
}

/// What the terms are calibrated on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fit {
    /// The first w seconds of the calibration trajectory.
    #[default]
    Single,
    /// The first w seconds of every trajectory but the scored one, each with its own
    /// clock (`[calibration.dive]`).
    Joint,
}

/// The clock a scored trajectory is corrected with.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Clock {
    /// The calibration's.
    #[default]
    Carried,
    /// Its own, re-found from its first `dive_s` seconds with the other terms carried
    /// (`[calibration.dive]`).
    Refound { dive_s: f64 },
}

impl Method {
    /// `model` calibrated on one trajectory, with its clock carried.
    pub fn single(model: impl Into<String>) -> Method {
        Method {
            model: model.into(),
            variant: Variant::default(),
        }
    }

    /// The same model, calibrated jointly over every other trajectory.
    pub fn jointly(self) -> Method {
        let variant = Variant {
            fit: Fit::Joint,
            ..self.variant
        };
        Method { variant, ..self }
    }

    /// The same method, scored with each trajectory's clock re-found from its first
    /// `dive_s` seconds.
    pub fn refound(self, dive_s: f64) -> Method {
        self.with_clock(Clock::Refound { dive_s })
    }

    /// The same method, scored with `clock`.
    pub fn with_clock(self, clock: Clock) -> Method {
        let variant = Variant {
            clock,
            ..self.variant
        };
        Method { variant, ..self }
    }

    /// Whether the terms are a joint fit's, whatever the clock.
    pub fn is_joint(&self) -> bool {
        self.variant.fit == Fit::Joint
    }

    /// Whether each scored trajectory's clock is re-found.
    pub fn is_refound(&self) -> bool {
        matches!(self.variant.clock, Clock::Refound { .. })
    }

    /// The method read from `label`: the variants its label ends with, and the rest as
    /// its model (a label that ends with no variant's words, or whose seconds are not
    /// written as [`Method`] writes them, is a model's). Reading never fails, and the
    /// method is written back as `label`, byte for byte.
    pub fn parse(label: &str) -> Method {
        match label.parse() {
            Ok(method) => method,
            Err(never) => match never {},
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.model)?;
        if self.variant.fit == Fit::Joint {
            f.write_str(JOINT)?;
        }
        if let Clock::Refound { dive_s } = self.variant.clock {
            write!(f, "{CLOCK_REFOUND}{dive_s}{SECONDS}")?;
        }
        Ok(())
    }
}

impl FromStr for Method {
    type Err = Infallible;

    fn from_str(label: &str) -> Result<Method, Infallible> {
        // The seconds as `Display` writes them, so that the label is written back as is.
        let seconds = |text: &str| {
            let dive_s: f64 = text.parse().ok()?;
            (dive_s.to_string() == text).then_some(dive_s)
        };
        let refound = label.rsplit_once(CLOCK_REFOUND).and_then(|(head, tail)| {
            let dive_s = seconds(tail.strip_suffix(SECONDS)?)?;
            Some((head, Clock::Refound { dive_s }))
        });
        let (head, clock) = refound.unwrap_or((label, Clock::Carried));
        let (model, fit) = match head.strip_suffix(JOINT) {
            Some(model) => (model, Fit::Joint),
            None => (head, Fit::Single),
        };
        Ok(Method {
            model: model.to_string(),
            variant: Variant { fit, clock },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_variant_is_written_as_its_label_and_read_back() {
        let model = "installation lever+offset+bias";
        let cases = [
            (Method::single(model), "installation lever+offset+bias"),
            (
                Method::single(model).jointly(),
                "installation lever+offset+bias, joint",
            ),
            (
                Method::single(model).refound(60.0),
                "installation lever+offset+bias, clock re-found in 60 s",
            ),
            (
                Method::single(model).jointly().refound(7.5),
                "installation lever+offset+bias, joint, clock re-found in 7.5 s",
            ),
            (
                Method::single("DCNet trained on the vehicle, replicate 2").refound(120.0),
                "DCNet trained on the vehicle, replicate 2, clock re-found in 120 s",
            ),
        ];
        for (method, label) in cases {
            assert_eq!(method.to_string(), label);
            assert_eq!(Method::parse(label), method, "{label}");
            assert_eq!(label.parse::<Method>().unwrap(), method, "{label}");
        }
        let joint = Method::parse("installation lever, joint, clock re-found in 60 s");
        assert!(joint.is_joint() && joint.is_refound());
        assert_eq!(joint.model, "installation lever");
        assert_eq!(joint.variant.clock, Clock::Refound { dive_s: 60.0 });
        let single = Method::parse("no calibration");
        assert!(!single.is_joint() && !single.is_refound());
    }

    /// Any text is read as a method and written back unchanged: what does not read as
    /// a variant stays in the model.
    #[test]
    fn a_label_is_written_back_byte_for_byte() {
        for label in [
            "",
            "baseline",
            ", joint",
            "a, joint, joint",
            "a, clock re-found in 60.0 s",
            "a, clock re-found in sixty s",
            "a, clock re-found in 60 s, joint",
            "a, clock re-found in 60",
            "a, clock re-found in 1e3 s",
        ] {
            assert_eq!(Method::parse(label).to_string(), label);
        }
        let unread = Method::parse("a, clock re-found in 60.0 s");
        assert!(!unread.is_refound());
        assert_eq!(unread.model, "a, clock re-found in 60.0 s");
        let after = Method::parse("a, clock re-found in 60 s, joint");
        assert!(after.is_joint() && !after.is_refound());
    }
}
