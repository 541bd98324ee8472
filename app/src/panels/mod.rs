//! The left panel's "Method" section: which LOD method builds, and the
//! parameters of each (one module per method). Everything here is persisted
//! between sessions.

pub mod simplify;

use serde::{Deserialize, Serialize};

use self::simplify::EdgeCollapseSettings;

/// The LOD methods the studio can build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Method {
    /// Edge collapse with a certified Hausdorff bound (hybrid paper §5.2).
    #[default]
    EdgeCollapse,
}

impl Method {
    /// Every method, in the order the list shows them.
    pub const ALL: &[Method] = &[Method::EdgeCollapse];

    pub fn name(self) -> &'static str {
        match self {
            Method::EdgeCollapse => "Edge collapse",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            Method::EdgeCollapse => {
                "Collapses edges in order of quadric error and certifies the result: a \
                 guaranteed bound on the two-sided Hausdorff distance between the original \
                 and the simplified surface (hybrid simplification paper, §5.2)."
            }
        }
    }
}

/// The chosen method, the parameters of every method, and how builds start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MethodSettings {
    pub method: Method,
    /// Rebuild by itself shortly after a parameter changes.
    pub auto_rebuild: bool,
    pub edge_collapse: EdgeCollapseSettings,
}

impl Default for MethodSettings {
    fn default() -> Self {
        MethodSettings {
            method: Method::default(),
            auto_rebuild: true,
            edge_collapse: EdgeCollapseSettings::default(),
        }
    }
}

impl MethodSettings {
    /// Settings restored from storage, with any value out of range (a hand-edited
    /// or older file) replaced, so a build never starts from nonsense.
    pub fn from_json(json: &str) -> Option<MethodSettings> {
        let mut settings: MethodSettings = serde_json::from_str(json).ok()?;
        settings.edge_collapse = settings.edge_collapse.sanitized();
        Some(settings)
    }

    pub fn to_json(&self) -> Option<String> {
        serde_json::to_string(self).ok()
    }

    /// The list of methods; true when the choice changed.
    pub fn method_list(&mut self, ui: &mut egui::Ui) -> bool {
        let before = self.method;
        for &method in Method::ALL {
            ui.selectable_value(&mut self.method, method, method.name())
                .on_hover_text(method.description());
        }
        self.method != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_round_trip_and_bad_values_are_replaced() {
        let settings = MethodSettings {
            auto_rebuild: false,
            edge_collapse: EdgeCollapseSettings {
                ratio: 0.3,
                ..Default::default()
            },
            ..Default::default()
        };
        let json = settings.to_json().expect("serialises");
        assert_eq!(MethodSettings::from_json(&json), Some(settings));

        let odd = r#"{"edge_collapse": {"ratio": 7.0, "min_quality": -2.0}}"#;
        let restored = MethodSettings::from_json(odd).expect("partial settings parse");
        assert!(restored.auto_rebuild, "missing fields take their defaults");
        assert_eq!(restored.edge_collapse.ratio, 1.0);
        assert_eq!(restored.edge_collapse.min_quality, 0.0);
        assert_eq!(MethodSettings::from_json("not json"), None);
    }
}
