//! Controls of the LOD chain: a table of rows LOD0…LODn (method, tolerance,
//! parameters; add, remove, reorder, duplicate) beside what each built, and
//! "Auto chain". What the controls set is `settings::chain`.

use lodstudio_core::bake::{DEFAULT_TEXTURE_SIZE, TEXTURE_SIZE_RANGE};
use lodstudio_core::hybrid::{KAPPA_RANGE, TAU_RANGE};
use lodstudio_core::recipe::{Row, RowTolerance};
use lodstudio_core::simplify::prune::TopologyMode;
use lodstudio_core::voxel::RESOLUTION_RANGE;

use crate::settings::Method;
use crate::settings::chain::{AUTO_ROWS_RANGE, AutoRule, ChainSettings};

/// Rows a chain may have (the table stays usable, the GLB small).
pub const MAX_ROWS: usize = 12;

const TOLERANCE_HINT: &str = "% of the bounding-box diagonal, pixels on the recipe's viewport \
    height, or a ratio of the input's primitives. The row's LOD is the coarsest cut within an \
    error, the finest within a ratio; LODs are ordered by certified bound. \"source\" is the \
    input itself (bound 0), LOD0 as engines expect it.";

/// What a built row shows in the table, formatted once when the chain is built.
#[derive(Debug, Clone, PartialEq)]
pub struct RowFigures {
    /// The LOD the row became (rows met by one cut share it).
    pub lod: usize,
    /// Triangles, points, splats, bound, pixels at the switch in, switch
    /// (coverage and distance), build seconds.
    pub cells: [String; 7],
    /// The bound is AMG's plane error, not a certified bound.
    pub estimate: bool,
    /// The triangle budget it fell short of, and why.
    pub unmet: Option<String>,
    /// Why the row does not earn its place (`recipe::Flag`): the words the
    /// table shows, and the hover's sentences.
    pub flags: Option<(String, String)>,
    /// The LOD wears its own baked texture: the words the flags column
    /// shows where it has no flag ("baked 2048²"), and why it was baked.
    pub baked: Option<(String, String)>,
}

/// The flags column's head and hover.
const FLAGS_HEAD: (&str, &str) = (
    "flags",
    "Rows that do not earn their place: the same LOD as a row before, never shown (it hands      over where it takes over), or costlier to draw than the finer LOD before it. Auto chain      leaves them out.",
);

/// The table's column heads after the editable ones.
pub const FIGURE_HEADS: [(&str, &str); 7] = [
    ("triangles", "Triangles of the row's LOD."),
    ("points", "Hybrid points of the row's LOD."),
    ("splats", "AMG splats of the row's LOD."),
    (
        "bound",
        "Error bound in % of the diagonal: certified, or ~ for AMG's plane error (the inspector gives it in model units for the LOD shown).",
    ),
    (
        "px in",
        "Pixels the bound covers where this LOD takes over (the popping a viewer may see).",
    ),
    (
        "switch out",
        "Screen coverage (object height / viewport) below which the next LOD takes over, and the camera distance in bounding radii.",
    ),
    (
        "build",
        "Seconds spent on the hierarchy behind the row (rows of one method and parameters share one); kept: taken from an earlier build or session, nothing rebuilt.",
    ),
];

/// What the table asks of the studio besides editing the recipe.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RowsResponse {
    /// The rows changed (the built chain is stale).
    pub changed: bool,
    /// A row's LOD label was clicked: show it.
    pub clicked: Option<usize>,
}

impl ChainSettings {
    /// The rows table; `figures[i]` is what row i built (when built with the
    /// rows as they are), `selected` the row shown.
    pub fn rows_ui(
        &mut self,
        ui: &mut egui::Ui,
        figures: Option<&[RowFigures]>,
        selected: Option<usize>,
    ) -> RowsResponse {
        let mut response = RowsResponse::default();
        let before = self.recipe.rows.clone();
        let mut action: Option<(usize, RowAction)> = None;
        egui::Grid::new("chain rows")
            .num_columns(6 + FIGURE_HEADS.len())
            .striped(true)
            .show(ui, |ui| {
                for head in ["row", "method", "tolerance", "parameters", ""] {
                    ui.strong(head);
                }
                for (head, hint) in FIGURE_HEADS.into_iter().chain([FLAGS_HEAD]) {
                    ui.strong(head).on_hover_text(hint);
                }
                ui.end_row();
                let rows = self.recipe.rows.len();
                for (i, row) in self.recipe.rows.iter_mut().enumerate() {
                    let fig = figures.and_then(|f| f.get(i));
                    let name = match fig {
                        Some(f) => format!("{i}: LOD{}", f.lod),
                        None => format!("{i}"),
                    };
                    if ui
                        .selectable_label(selected == Some(i), name)
                        .on_hover_text("Show this row's LOD")
                        .clicked()
                    {
                        response.clicked = Some(i);
                    }
                    method_menu(ui, row);
                    tolerance_ui(ui, row);
                    parameters_ui(ui, row);
                    // The row's moves in one menu, so the table fits 1280 px.
                    ui.menu_button("Edit", |ui| {
                        for (text, enabled, what) in [
                            ("Up", i > 0, RowAction::Up),
                            ("Down", i + 1 < rows, RowAction::Down),
                            ("Duplicate", rows < MAX_ROWS, RowAction::Duplicate),
                            ("Remove", rows > 1, RowAction::Remove),
                        ] {
                            if ui.add_enabled(enabled, egui::Button::new(text)).clicked() {
                                action = Some((i, what));
                                ui.close();
                            }
                        }
                        bake_ui(ui, row);
                        topology_ui(ui, row);
                    })
                    .response
                    .on_hover_text(
                        "Move, duplicate or remove this row; bake its own texture; free its \
                         topology.",
                    );
                    match fig {
                        Some(f) => {
                            for (c, cell) in f.cells.iter().enumerate() {
                                // Figures in monospace: columns keep their width.
                                if let (0, Some(why)) = (c, &f.unmet) {
                                    ui.monospace(format!("!{cell}")).on_hover_text(why);
                                } else if c == 3 && f.estimate {
                                    ui.monospace(format!("~{cell}")).on_hover_text(
                                        "AMG's plane error: an estimate, not a certified bound",
                                    );
                                } else {
                                    ui.monospace(cell);
                                }
                            }
                            match (&f.flags, &f.baked) {
                                (Some((words, why)), _) => {
                                    let warn = ui.visuals().warn_fg_color;
                                    ui.colored_label(warn, words).on_hover_text(why);
                                }
                                (None, Some((words, why))) => {
                                    ui.weak(words).on_hover_text(why);
                                }
                                (None, None) => {
                                    ui.label("");
                                }
                            }
                        }
                        None => {
                            for _ in 0..=FIGURE_HEADS.len() {
                                ui.weak("–");
                            }
                        }
                    }
                    ui.end_row();
                }
            });
        let rows = &mut self.recipe.rows;
        match action {
            Some((i, RowAction::Up)) => rows.swap(i - 1, i),
            Some((i, RowAction::Down)) => rows.swap(i, i + 1),
            Some((i, RowAction::Duplicate)) => rows.insert(i + 1, rows[i].clone()),
            Some((i, RowAction::Remove)) => {
                rows.remove(i);
            }
            None => {}
        }
        response.changed = self.recipe.rows != before;
        response
    }

    /// "Add row": a row coarser than the last; true when one was added.
    pub fn add_row_ui(&mut self, ui: &mut egui::Ui) -> bool {
        let rows = &mut self.recipe.rows;
        let add = ui
            .add_enabled(rows.len() < MAX_ROWS, egui::Button::new("Add row"))
            .on_hover_text("A row coarser than the last: its tolerance doubled.");
        if add.clicked() {
            let next = rows
                .last()
                .map(coarser)
                .unwrap_or_else(|| Row::new(Method::EdgeCollapse, RowTolerance::Percent(1.0)));
            rows.push(next);
        }
        add.clicked()
    }

    /// "Auto chain": its rule and its button; true when clicked (the
    /// studio replaces the rows by the rule's and builds them, leaving out
    /// the rows the chain flags).
    pub fn auto_ui(&mut self, ui: &mut egui::Ui) -> bool {
        let a = &mut self.auto;
        ui.horizontal_wrapped(|ui| {
            choose(
                ui,
                &mut a.rule,
                [AutoRule::HalveTriangles, AutoRule::DoublePixels],
                rule_name,
            );
            choose(ui, &mut a.method, Method::ALL, Method::tag);
            ui.checkbox(&mut a.source, "source first")
                .on_hover_text("LOD0 is the source itself (bound 0), as engines expect; the rule's rows follow it.");
            let first = match (a.rule, a.source) {
                (AutoRule::HalveTriangles, false) => "LOD0 ratio",
                (AutoRule::HalveTriangles, true) => "LOD1 ratio",
                (AutoRule::DoublePixels, false) => "LOD0 px",
                (AutoRule::DoublePixels, true) => "LOD1 px",
            };
            let range = a.first_range();
            ui.add(
                egui::DragValue::new(&mut a.first)
                    .range(range)
                    .speed(0.01)
                    .prefix(format!("{first} ")),
            );
            ui.add(
                egui::DragValue::new(&mut a.rows)
                    .range(AUTO_ROWS_RANGE)
                    .prefix("rows "),
            );
            ui.checkbox(&mut a.impostor, "AMG impostor last")
                .on_hover_text("Close the chain with an AMG splat impostor (15% of the diagonal).");
        });
        *a = a.sanitized();
        ui.button("Auto chain")
            .on_hover_text("Replace the rows by the rule (halve the triangles, or double the pixel error, row after row) and build them; rows that give the same LOD as a row before, are never shown or cost more to draw than the finer LOD are left out.")
            .clicked()
    }
}

#[derive(Debug, Clone, Copy)]
enum RowAction {
    Up,
    Down,
    Duplicate,
    Remove,
}

fn rule_name(rule: AutoRule) -> &'static str {
    match rule {
        AutoRule::HalveTriangles => "halve the triangles",
        AutoRule::DoublePixels => "double the pixel error",
    }
}

/// A menu of `options` under a button named by the value (the button's
/// text is its accessible name, unlike a combo box's).
fn choose<T: PartialEq + Copy>(
    ui: &mut egui::Ui,
    value: &mut T,
    options: impl IntoIterator<Item = T>,
    name: impl Fn(T) -> &'static str,
) {
    ui.menu_button(name(*value), |ui| {
        for option in options {
            ui.selectable_value(value, option, name(option));
        }
    });
}

/// The row after `row`: the same method, its tolerance doubled (a ratio halved).
fn coarser(row: &Row) -> Row {
    let tolerance = match row.tolerance {
        RowTolerance::Percent(p) => RowTolerance::Percent((2.0 * p).min(100.0)),
        RowTolerance::Pixels(p) => RowTolerance::Pixels(2.0 * p),
        RowTolerance::Ratio(r) => RowTolerance::Ratio((0.5 * r).max(1e-4)),
        RowTolerance::Source => RowTolerance::Ratio(0.5),
    };
    Row {
        tolerance,
        ..row.clone()
    }
}

/// The method of a row; a new method takes its own default parameters.
fn method_menu(ui: &mut egui::Ui, row: &mut Row) {
    let mut method = row.method;
    choose(ui, &mut method, Method::CHAIN, Method::tag);
    if method != row.method {
        *row = Row::new(method, row.tolerance);
    }
}

/// The tolerance's number and unit.
fn tolerance_ui(ui: &mut egui::Ui, row: &mut Row) {
    ui.horizontal(|ui| {
        let (mut value, unit) = match row.tolerance {
            RowTolerance::Percent(v) => (v, 0),
            RowTolerance::Pixels(v) => (v, 1),
            RowTolerance::Ratio(v) => (v, 2),
            RowTolerance::Source => (1.0, 3),
        };
        // Dragging stays in these ranges; a value from a recipe outside them
        // (any the recipe accepts) is shown as it is, not clamped.
        let range = match unit {
            0 => 0.0..=100.0,
            1 => 0.0..=10_000.0,
            _ => 1e-6..=1.0,
        };
        if unit != 3 {
            ui.add(
                egui::DragValue::new(&mut value)
                    .range(range)
                    .clamp_existing_to_range(false)
                    .speed(0.01)
                    .max_decimals(6),
            )
            .on_hover_text(TOLERANCE_HINT);
        }
        let mut new_unit = unit;
        choose(ui, &mut new_unit, 0..4, |u| {
            ["%", "px", "ratio", "source"][u]
        });
        row.tolerance = match (new_unit, new_unit == unit) {
            (3, _) => RowTolerance::Source,
            (0, true) => RowTolerance::Percent(value),
            (1, true) => RowTolerance::Pixels(value),
            (_, true) => RowTolerance::Ratio(value),
            // Another unit starts from a sensible value of its own.
            (0, false) => RowTolerance::Percent(1.0),
            (1, false) => RowTolerance::Pixels(1.0),
            (_, false) => RowTolerance::Ratio(0.5),
        };
    });
}

const BAKE_HINT: &str = "Give this LOD its own texture: a new UV atlas with the model's \
    colours (factor × texture × vertex colour) and a normal map of its shading transferred \
    onto it. Its seams then stop nothing, so a textured model reaches any triangle budget; \
    one material, one primitive.";

const SHORT_HINT: &str = "Checked, a textured model's row bakes its own texture where its \
    seams keep it short of its triangle budget, or where baked it measures closer to the model \
    (colour and shading, compared at points of both candidates); unchecked, it keeps the \
    model's atlas and stops where its seams do.";

const TEXTURE_HINT: &str = "The baked texture's side. auto: the model's texels per triangle \
    kept (its textures' texels × the share of its triangles this LOD keeps), 1024 to 4096 px; \
    drag to set one.";

const TOPOLOGY_HINT: &str = "Checked, this edge-collapse row may remove whole small pieces \
    (specks, loose parts), and merge nearby pieces and close holes and handles by contracting \
    close vertices, where its certified two-sided bound, which covers what changed, \
    stays within the row's budget: a count the pieces and handles kept out of reach is met. \
    Unchecked, every piece and handle is kept (\"topology\": \"keep\").";

/// Whether an edge-collapse row may change topology (`"topology": "free"`).
fn topology_ui(ui: &mut egui::Ui, row: &mut Row) {
    if row.method != Method::EdgeCollapse || row.tolerance == RowTolerance::Source {
        return;
    }
    ui.separator();
    let mut free = row.frees_topology();
    if ui
        .checkbox(&mut free, "Free topology")
        .on_hover_text(TOPOLOGY_HINT)
        .changed()
    {
        row.topology = free.then_some(TopologyMode::Free);
    }
}

/// Whether the row bakes its own texture (always, when short of its budget,
/// or never), and at what size (not a source row).
fn bake_ui(ui: &mut egui::Ui, row: &mut Row) {
    if row.tolerance == RowTolerance::Source || row.method == Method::Impostor {
        return;
    }
    ui.separator();
    let mut always = row.bakes();
    ui.checkbox(&mut always, "Bake its own texture")
        .on_hover_text(BAKE_HINT);
    let mut when_short = row.bake.is_none();
    if !always {
        ui.checkbox(&mut when_short, "…or where that helps")
            .on_hover_text(SHORT_HINT);
    }
    row.bake = match (always, when_short) {
        (true, _) => Some(true),
        (false, true) => None,
        (false, false) => Some(false),
    };
    row.texture = match row.bake != Some(false) {
        true => {
            // Unset, the bake picks the model's texels per triangle kept.
            let auto = row.texture.is_none();
            let mut size = row.texture.unwrap_or(DEFAULT_TEXTURE_SIZE);
            let changed = ui
                .add(
                    egui::DragValue::new(&mut size)
                        .range(TEXTURE_SIZE_RANGE)
                        .prefix("texture ")
                        .custom_formatter(move |n, _| match auto {
                            true => "auto".into(),
                            false => format!("{n} px"),
                        }),
                )
                .on_hover_text(TEXTURE_HINT)
                .changed();
            // A row that may bake says its size once it bakes or is given one.
            (row.bakes() || changed || row.texture.is_some()).then_some(size)
        }
        false => None,
    };
}

/// The parameters of the row's method: κ, τ (hybrid), resolution (voxel).
fn parameters_ui(ui: &mut egui::Ui, row: &mut Row) {
    ui.horizontal(|ui| match row.method {
        Method::Hybrid => {
            let (mut kappa, mut tau) = (row.kappa(), row.tau());
            ui.add(
                egui::DragValue::new(&mut kappa)
                    .range(KAPPA_RANGE)
                    .speed(0.05)
                    .prefix("κ "),
            );
            ui.add(
                egui::DragValue::new(&mut tau)
                    .range(TAU_RANGE)
                    .speed(0.05)
                    .prefix("τ "),
            );
            (row.kappa, row.tau) = (Some(kappa), Some(tau));
        }
        Method::Voxel => {
            let mut resolution = row.resolution();
            ui.add(
                egui::DragValue::new(&mut resolution)
                    .range(RESOLUTION_RANGE)
                    .prefix("resolution "),
            );
            row.resolution = Some(resolution);
        }
        Method::Impostor => {
            let defaults = lodstudio_core::impostor::ImpostorOptions::default();
            let (mut views, mut texture) = (
                row.views.unwrap_or(defaults.views),
                row.texture.unwrap_or(defaults.texture),
            );
            ui.add(
                egui::DragValue::new(&mut views)
                    .range(lodstudio_core::impostor::VIEWS_RANGE)
                    .prefix("views ")
                    .suffix("²"),
            )
            .on_hover_text("Frames per side of the octahedral map of views.");
            ui.add(
                egui::DragValue::new(&mut texture)
                    .range(TEXTURE_SIZE_RANGE)
                    .prefix("atlas ")
                    .suffix(" px"),
            );
            (row.views, row.texture) = (Some(views), Some(texture));
        }
        _ => {
            ui.weak("defaults");
        }
    });
}
