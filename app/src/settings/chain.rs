//! The LOD chain the studio authors: its recipe (core's `recipe::Recipe`,
//! the very file `lodstudio export --recipe` replays) and the rule "Auto
//! chain" fills it by, like the auto LOD of game engines: halve the
//! triangles, or double the pixel error, from a first row down to a floor,
//! optionally closed by an AMG splat impostor.

use std::ops::RangeInclusive;

use lodstudio_core::recipe::{Recipe, Row, RowTolerance, parse_lods};
use serde::{Deserialize, Serialize};

use super::Method;

/// How many rows "Auto chain" makes (the impostor included).
pub const AUTO_ROWS_RANGE: RangeInclusive<usize> = 2..=8;
/// The first row's triangle ratio (halving) or pixel error (doubling).
pub const FIRST_RATIO_RANGE: RangeInclusive<f32> = 0.01..=1.0;
pub const FIRST_PIXELS_RANGE: RangeInclusive<f32> = 0.25..=64.0;
/// The impostor's error in % of the diagonal.
const IMPOSTOR_PERCENT: f32 = 15.0;

/// The rule of "Auto chain".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum AutoRule {
    /// Each row half the triangles of the one before (a ratio of the input).
    #[default]
    HalveTriangles,
    /// Each row twice the pixel error of the one before.
    DoublePixels,
}

/// What "Auto chain" makes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AutoChain {
    pub rule: AutoRule,
    /// The rows' method (the impostor aside).
    pub method: Method,
    /// LOD0's ratio (halving) or pixels (doubling).
    pub first: f32,
    pub rows: usize,
    /// Close the chain with an AMG splat impostor.
    pub impostor: bool,
    /// LOD0 is the source itself (engines expect it), the rule's rows after it.
    pub source: bool,
}

impl Default for AutoChain {
    fn default() -> Self {
        AutoChain {
            rule: AutoRule::HalveTriangles,
            method: Method::EdgeCollapse,
            first: 0.5,
            rows: 4,
            impostor: false,
            source: true,
        }
    }
}

impl AutoChain {
    pub fn first_range(&self) -> RangeInclusive<f32> {
        match self.rule {
            AutoRule::HalveTriangles => FIRST_RATIO_RANGE,
            AutoRule::DoublePixels => FIRST_PIXELS_RANGE,
        }
    }

    pub fn sanitized(self) -> AutoChain {
        let d = AutoChain::default();
        let mut s = AutoChain {
            rows: self
                .rows
                .clamp(*AUTO_ROWS_RANGE.start(), *AUTO_ROWS_RANGE.end()),
            ..self
        };
        s.first = super::clamp_or(
            self.first,
            s.first_range(),
            d.first.min(*s.first_range().end()),
        );
        s
    }

    /// The rows of the rule: the source as LOD0 (when asked), then `first`,
    /// each next halved or doubled.
    pub fn make(&self) -> Vec<Row> {
        let s = self.sanitized();
        let own = s.rows - usize::from(s.impostor) - usize::from(s.source);
        let source = s
            .source
            .then(|| Row::new(Method::EdgeCollapse, RowTolerance::Source));
        let mut rows: Vec<Row> = source.into_iter().collect();
        rows.extend((0..own).map(|i| {
            let step = 2f32.powi(i as i32);
            let tolerance = match s.rule {
                AutoRule::HalveTriangles => RowTolerance::Ratio(s.first / step),
                AutoRule::DoublePixels => RowTolerance::Pixels(s.first * step),
            };
            Row::new(s.method, tolerance)
        }));
        if s.impostor {
            rows.push(Row::new(
                Method::Amg,
                RowTolerance::Percent(IMPOSTOR_PERCENT),
            ));
        }
        rows
    }
}

/// The chain on the studio's chain panel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ChainSettings {
    pub recipe: Recipe,
    pub auto: AutoChain,
}

impl Default for ChainSettings {
    fn default() -> Self {
        let rows = parse_lods("source,simplify:0.5%,simplify:2%,amg:15%", None)
            .expect("the default rows parse");
        ChainSettings {
            recipe: Recipe::new(rows),
            auto: AutoChain::default(),
        }
    }
}

impl ChainSettings {
    /// A chain read back from a session: a recipe that fails its checks is
    /// replaced by the default one (never reaches a build).
    pub fn sanitized(self) -> ChainSettings {
        ChainSettings {
            recipe: match self.recipe.check() {
                Ok(()) => self.recipe,
                Err(_) => ChainSettings::default().recipe,
            },
            auto: self.auto.sanitized(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_chains_halve_or_double_and_end_with_an_impostor() {
        let halve = AutoChain {
            first: 0.5,
            rows: 4,
            impostor: true,
            ..Default::default()
        };
        let rows = halve.make();
        let labels: Vec<String> = rows.iter().map(Row::label).collect();
        assert_eq!(
            labels,
            ["source", "simplify:0.5", "simplify:0.25", "amg:15%"],
            "LOD0 is the source by default"
        );
        let double = AutoChain {
            rule: AutoRule::DoublePixels,
            method: Method::Hybrid,
            first: 1.0,
            rows: 3,
            impostor: false,
            source: false,
        };
        let labels: Vec<String> = double.make().iter().map(Row::label).collect();
        assert_eq!(labels, ["hybrid:1px", "hybrid:2px", "hybrid:4px"]);
        // Every auto chain is a valid recipe, even from absurd settings.
        for bad in [
            AutoChain {
                rows: 99,
                first: f32::NAN,
                ..halve
            },
            AutoChain {
                rows: 0,
                first: -3.0,
                ..double
            },
        ] {
            let r = Recipe::new(bad.make());
            assert!(r.check().is_ok(), "{r:?}");
            assert!(AUTO_ROWS_RANGE.contains(&r.rows.len()));
        }
    }
}
