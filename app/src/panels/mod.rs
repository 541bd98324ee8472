//! The left panel's "Method" section: the list of methods and each one's
//! controls, and the 3D Tiles section (`tiles`) (`*_ui`-style: each takes its settings by `&mut`). What the
//! controls set lives in `settings`, which builds use without any UI.

pub mod amg;
pub mod chain;
pub mod hybrid;
pub mod mergetree;
pub mod simplify;
pub mod threshold;
pub mod tiles;
pub mod voxel;

use crate::settings::{Method, MethodSettings};

impl MethodSettings {
    /// The list of methods; true when the choice changed.
    pub fn method_list(&mut self, ui: &mut egui::Ui) -> bool {
        let before = self.method;
        for method in Method::ALL {
            ui.selectable_value(&mut self.method, method, method.name())
                .on_hover_text(method.description());
        }
        self.method != before
    }
}
