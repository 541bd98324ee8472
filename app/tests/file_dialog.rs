//! The in-app file browser, driven headlessly (egui_kittest). Alone in its
//! test binary: the browser's queue of questions is process-wide, as a
//! desktop's dialog service is, so another studio drawn in the same process
//! would answer them.

use std::time::{Duration, Instant};

// Shared with the other GUI tests and the bench, which use the rest of it.
#[allow(dead_code)]
mod common;

use common::{studio, wait_while};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::studio::StudioApp;

/// Without a desktop portal (containers, remote sessions), Save recipe…
/// opens the in-app file browser, and a path typed there receives the
/// recipe (issue 46).
#[test]
fn the_in_app_file_dialog_saves_a_recipe_to_a_typed_path() {
    use egui::accesskit::Role;
    lodstudio::file_dialog::set_mode(lodstudio::file_dialog::Mode::InApp);
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("typed-recipe.json");
    let mut harness = studio(None);
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    harness.get_by_label("Save recipe…").click();
    // The save's worker asks; a frame shows the browser with the name.
    let name_field = |h: &Harness<'_, StudioApp>| {
        h.query_all_by_role_and_label(Role::TextInput, "File name")
            .any(|n| n.value().is_some_and(|v| v.ends_with("-recipe.json")))
    };
    let start = Instant::now();
    while !name_field(&harness) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no browser shown"
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    harness
        .get_by_role_and_label(Role::TextInput, "File name")
        .focus();
    harness.run();
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness
        .get_by_role_and_label(Role::TextInput, "File name")
        .type_text(target.to_str().unwrap());
    harness.run();
    harness.get_by_label("Save").click();
    let start = Instant::now();
    while !target.exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "nothing written");
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    harness.run();
    assert_eq!(
        std::fs::read(&target).unwrap(),
        harness.state().chain_settings().recipe.to_json()
    );
}
