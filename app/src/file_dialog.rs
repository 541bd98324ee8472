//! Where the studio asks for a path: the desktop's own dialog (rfd, through
//! the XDG desktop portal on Linux), or, where the desktop has none
//! (containers, remote sessions, bare window managers: rfd then answers
//! nothing at once), the studio's in-app file browser.
//!
//! The browser is written here. Of the maintained egui file-dialog crates,
//! `egui-file-dialog` 0.15 (search, pinned folders) is built on egui 0.36
//! and would bring a second egui beside the studio's 0.37, and `egui_file`
//! 0.29 (on 0.37) draws its titles and entries with emoji (💾, 🗀, 🗋) that
//! egui 0.37's bundled fonts lack: boxes in the studio, a panic under
//! egui_kittest. What the studio needs is small: a folder, its entries, a
//! name, recent folders, and a question before replacing a file.
//!
//! Dialogs are asked for from worker threads (an export asks, then writes),
//! so [`pick_file`] and [`save_file`] block their caller: with no native
//! dialog, the request waits in a queue until the studio's frame shows it
//! ([`InApp::ui`]) and the user answers. Nothing else changes for the
//! callers.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc::{self, Sender};
use std::sync::{Mutex, PoisonError};

/// Which dialog the studio shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// The desktop's, where its portal is installed; else the in-app one.
    Auto,
    Native,
    InApp,
}

/// `Auto` unless `LODSTUDIO_FILE_DIALOG=native|in-app` or [`set_mode`] say.
static MODE: AtomicU8 = AtomicU8::new(0);

/// Chooses the dialog (the studio's menu, tests).
pub fn set_mode(mode: Mode) {
    MODE.store(mode as u8 + 1, Ordering::Relaxed);
}

fn mode() -> Mode {
    match MODE.load(Ordering::Relaxed) {
        1 => Mode::Auto,
        2 => Mode::Native,
        3 => Mode::InApp,
        _ => match std::env::var("LODSTUDIO_FILE_DIALOG").as_deref() {
            Ok("native") => Mode::Native,
            Ok("in-app") => Mode::InApp,
            _ => Mode::Auto,
        },
    }
}

/// Whether the desktop's dialog can be shown. On Linux rfd goes through the
/// XDG desktop portal: it needs a session bus and the portal installed (its
/// D-Bus activation file); elsewhere the system's dialog is always there.
pub fn native_available() -> bool {
    match mode() {
        Mode::Native => true,
        Mode::InApp => false,
        Mode::Auto if cfg!(target_os = "linux") => {
            std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|a| !a.is_empty())
                && ["/usr/share", "/usr/local/share"].iter().any(|d| {
                    Path::new(d)
                        .join("dbus-1/services/org.freedesktop.portal.Desktop.service")
                        .exists()
                })
        }
        Mode::Auto => true,
    }
}

/// File types a dialog offers: a name and its extensions.
pub type Filters<'a> = &'a [(&'a str, &'a [&'a str])];

/// The desktop's dialog with `title` and `filters`.
fn native(title: &str, filters: Filters) -> rfd::FileDialog {
    filters
        .iter()
        .fold(rfd::FileDialog::new().set_title(title), |d, (name, ext)| {
            d.add_filter(*name, ext)
        })
}

/// A file to open, or `None` when the user closed the dialog.
pub fn pick_file(title: &str, filters: Filters) -> Option<PathBuf> {
    if native_available() {
        return native(title, filters).pick_file();
    }
    ask(Request::new(title, None, filters))
}

/// Where to save (suggesting `file_name`), or `None` when the user closed
/// the dialog. Both dialogs ask before replacing a file.
pub fn save_file(title: &str, file_name: &str, filters: Filters) -> Option<PathBuf> {
    if native_available() {
        return native(title, filters).set_file_name(file_name).save_file();
    }
    ask(Request::new(title, Some(file_name), filters))
}

/// One question for the in-app browser.
struct Request {
    title: String,
    /// `Some(suggested name)` for a save.
    save: Option<String>,
    /// Extensions it offers, the first the one a bare name gets.
    extensions: Vec<String>,
    reply: Option<Sender<Option<PathBuf>>>,
}

impl Request {
    fn new(title: &str, save: Option<&str>, filters: Filters) -> Request {
        Request {
            title: title.to_string(),
            save: save.map(str::to_string),
            extensions: filters
                .iter()
                .flat_map(|(_, ext)| ext.iter().map(|e| e.to_string()))
                .collect(),
            reply: None,
        }
    }

    fn answer(&mut self, path: Option<PathBuf>) {
        if let Some(reply) = self.reply.take() {
            // The asker may have gone (its job dropped): nobody to tell.
            let _ = reply.send(path);
        }
    }
}

/// Questions waiting for the studio's frame, and the context that draws it.
struct Queue {
    pending: VecDeque<Request>,
    ctx: Option<egui::Context>,
    /// Folders answers came from, newest first.
    recent: Vec<PathBuf>,
}

static QUEUE: Mutex<Queue> = Mutex::new(Queue {
    pending: VecDeque::new(),
    ctx: None,
    recent: Vec::new(),
});

fn queue() -> std::sync::MutexGuard<'static, Queue> {
    QUEUE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Folders offered beside the browser.
const MAX_RECENT: usize = 6;

/// Queues `request` and waits for the in-app browser's answer.
fn ask(mut request: Request) -> Option<PathBuf> {
    let (tx, rx) = mpsc::channel();
    request.reply = Some(tx);
    let ctx = {
        let mut q = queue();
        q.pending.push_back(request);
        q.ctx.clone()
    };
    if let Some(ctx) = ctx {
        ctx.request_repaint();
    }
    rx.recv().ok().flatten()
}

/// The in-app browser: the question shown, if any.
#[derive(Default)]
pub struct InApp {
    showing: Option<Showing>,
}

struct Showing {
    request: Request,
    browser: Browser,
    /// A chosen file that exists, waiting for "Replace".
    replace: Option<PathBuf>,
}

impl InApp {
    /// Shows the next question, answers it when the user chooses or closes.
    pub fn ui(&mut self, ctx: &egui::Context) {
        if self.showing.is_none() {
            let mut q = queue();
            if q.ctx.as_ref() != Some(ctx) {
                q.ctx = Some(ctx.clone());
            }
            let Some(request) = q.pending.pop_front() else {
                return;
            };
            let folder = q.recent.first().cloned();
            drop(q);
            self.showing = Some(Showing::new(request, folder));
        }
        let Some(showing) = &mut self.showing else {
            return;
        };
        if let Some(answer) = showing.ui(ctx)
            && let Some(mut showing) = self.showing.take()
        {
            if let Some(folder) = answer.as_deref().and_then(Path::parent) {
                let mut q = queue();
                q.recent.retain(|f| f != folder);
                q.recent.insert(0, folder.to_path_buf());
                q.recent.truncate(MAX_RECENT);
            }
            showing.request.answer(answer);
            ctx.request_repaint();
        }
    }
}

impl Drop for InApp {
    /// Nobody will answer: every asker gets `None` instead of waiting.
    fn drop(&mut self) {
        if let Some(mut s) = self.showing.take() {
            s.request.answer(None);
        }
        for mut r in queue().pending.drain(..) {
            r.answer(None);
        }
    }
}

/// The folder shown, its entries and the name typed.
struct Browser {
    folder: PathBuf,
    /// The folder field as typed (Enter goes there).
    folder_edit: String,
    /// Sub-folders, then the files the request offers, by name.
    entries: Vec<(String, bool)>,
    name: String,
    note: Option<String>,
}

impl Browser {
    fn new(folder: PathBuf, name: String, extensions: &[String]) -> Browser {
        let mut browser = Browser {
            folder: PathBuf::new(),
            folder_edit: String::new(),
            entries: Vec::new(),
            name,
            note: None,
        };
        browser.go(folder, extensions);
        browser
    }

    /// Shows `folder` (a folder it cannot read keeps the one shown).
    fn go(&mut self, folder: PathBuf, extensions: &[String]) {
        let read = std::fs::read_dir(&folder).map(|dir| {
            let mut entries: Vec<(String, bool)> = dir
                .filter_map(Result::ok)
                .filter_map(|e| {
                    let name = e.file_name().to_str()?.to_string();
                    let is_dir = e.path().is_dir();
                    let offered = is_dir || offers(&e.path(), extensions);
                    (!name.starts_with('.') && offered).then_some((name, is_dir))
                })
                .collect();
            entries.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
            entries
        });
        match read {
            Ok(entries) => {
                self.entries = entries;
                self.folder_edit = folder.display().to_string();
                self.folder = folder;
                self.note = None;
            }
            Err(e) => self.note = Some(format!("{}: {e}", folder.display())),
        }
    }
}

/// Whether a file's extension is one the request offers (any, if none).
fn offers(path: &Path, extensions: &[String]) -> bool {
    extensions.is_empty()
        || path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
}

impl Showing {
    fn new(request: Request, folder: Option<PathBuf>) -> Showing {
        let start = folder
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_default();
        let name = request.save.clone().unwrap_or_default();
        let browser = Browser::new(start, name, &request.extensions);
        Showing {
            request,
            browser,
            replace: None,
        }
    }

    /// Draws the browser (or the question before replacing a file);
    /// `Some(answer)` once the user answered.
    fn ui(&mut self, ctx: &egui::Context) -> Option<Option<PathBuf>> {
        if let Some(path) = self.replace.clone() {
            return self.replace_ui(ctx, path);
        }
        let recent = queue().recent.clone();
        let extensions = self.request.extensions.clone();
        let saving = self.request.save.is_some();
        let mut answer = None;
        let mut open = true;
        egui::Window::new(self.request.title.as_str())
            .open(&mut open)
            .collapsible(false)
            .default_size([560.0, 380.0])
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .show(ctx, |ui| {
                let b = &mut self.browser;
                ui.horizontal(|ui| {
                    if ui
                        .button("Up")
                        .on_hover_text("The parent folder.")
                        .clicked()
                        && let Some(parent) = b.folder.parent()
                    {
                        b.go(parent.to_path_buf(), &extensions);
                    }
                    let label = ui.label("Folder");
                    let edit = ui
                        .add(
                            egui::TextEdit::singleline(&mut b.folder_edit)
                                .desired_width(f32::INFINITY),
                        )
                        .labelled_by(label.id);
                    if edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                        b.go(PathBuf::from(b.folder_edit.trim()), &extensions);
                    }
                });
                if !recent.is_empty() {
                    ui.horizontal_wrapped(|ui| {
                        ui.weak("Recent:");
                        for folder in &recent {
                            let name = folder.file_name().map_or_else(
                                || folder.display().to_string(),
                                |n| n.to_string_lossy().into_owned(),
                            );
                            let button = ui.small_button(name);
                            if button.on_hover_text(folder.display().to_string()).clicked() {
                                b.go(folder.clone(), &extensions);
                            }
                        }
                    });
                }
                ui.separator();
                let mut go_to = None;
                egui::ScrollArea::vertical()
                    .max_height(220.0)
                    .auto_shrink([false, true])
                    .show(ui, |ui| {
                        for (name, is_dir) in &b.entries {
                            let label = if *is_dir {
                                format!("{name}/")
                            } else {
                                name.clone()
                            };
                            let row = ui.selectable_label(!is_dir && b.name == *name, label);
                            if row.clicked() {
                                match is_dir {
                                    true => go_to = Some(b.folder.join(name)),
                                    false => b.name = name.clone(),
                                }
                            }
                            if row.double_clicked() && !is_dir {
                                answer = Some(b.folder.join(name));
                            }
                        }
                    });
                if let Some(folder) = go_to {
                    b.go(folder, &extensions);
                }
                ui.separator();
                ui.horizontal(|ui| {
                    let label = ui.label("File name");
                    ui.add(egui::TextEdit::singleline(&mut b.name).desired_width(f32::INFINITY))
                        .labelled_by(label.id);
                });
                if let Some(note) = &b.note {
                    ui.colored_label(ui.visuals().error_fg_color, note);
                }
                ui.horizontal(|ui| {
                    let verb = if saving { "Save" } else { "Open" };
                    let name = b.name.trim();
                    if ui
                        .add_enabled(!name.is_empty(), egui::Button::new(verb))
                        .clicked()
                    {
                        // A typed path may be absolute; `join` then takes it whole.
                        answer = Some(b.folder.join(name));
                    }
                    if ui.button("Cancel").clicked() {
                        answer = Some(PathBuf::new());
                    }
                });
            });
        if !open {
            return Some(None);
        }
        let path = answer?;
        if path.as_os_str().is_empty() {
            return Some(None);
        }
        if !saving {
            if path.is_file() {
                return Some(Some(path));
            }
            self.browser.note = Some(format!("{}: no such file", path.display()));
            return None;
        }
        let path = with_extension(path, &extensions);
        if path.exists() {
            self.replace = Some(path);
            return None;
        }
        Some(Some(path))
    }

    fn replace_ui(&mut self, ctx: &egui::Context, path: PathBuf) -> Option<Option<PathBuf>> {
        let mut answer = None;
        egui::Window::new("Replace the file?")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .show(ctx, |ui| {
                ui.label(format!("{} exists. Replace it?", path.display()));
                ui.horizontal(|ui| {
                    if ui.button("Replace").clicked() {
                        answer = Some(Some(path.clone()));
                    }
                    if ui.button("Choose another").clicked() {
                        self.replace = None;
                    }
                });
            });
        answer
    }
}

/// A saved file's name with an extension the dialog offers (the first when
/// the user typed none).
fn with_extension(path: PathBuf, extensions: &[String]) -> PathBuf {
    match extensions.first() {
        Some(first) if !offers(&path, extensions) => {
            let mut name = path.into_os_string();
            name.push(".");
            name.push(first);
            PathBuf::from(name)
        }
        _ => path,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_name_takes_the_first_offered_extension() {
        let ext = vec!["glb".to_string(), "gltf".to_string()];
        assert_eq!(
            with_extension("a/chain".into(), &ext),
            PathBuf::from("a/chain.glb")
        );
        assert_eq!(
            with_extension("a/chain.GLTF".into(), &ext),
            PathBuf::from("a/chain.GLTF")
        );
        assert_eq!(
            with_extension("a/chain.v2".into(), &ext),
            PathBuf::from("a/chain.v2.glb")
        );
        assert_eq!(with_extension("a/x".into(), &[]), PathBuf::from("a/x"));
    }
}
