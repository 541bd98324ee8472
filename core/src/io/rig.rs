//! What moves a glTF scene's meshes: each node's rest transform and
//! parent, each skin's joints and inverse bind matrices, and each
//! animation's channels (glTF 2.0 §3.7.3 skins, §3.11 animations), read
//! so that a skinned mesh can be posed (`scene::pose`). Accessors are
//! checked against their buffers before any read, as for meshes.

use glam::{Mat4, Quat, Vec3};

use super::error::{ParseError, ParseResult};
use super::gltf::check_accessor;

/// A node's rest transform, as translation, rotation and scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Trs {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// One skin: its joints (node indices) and their inverse bind matrices.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinDef {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
}

/// Which property a channel drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
}

/// One animation channel: keyframe times and values (vec3 or quaternion
/// as xyzw), with its sampler's interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub path: Path,
    pub times: Vec<f32>,
    pub values: Vec<[f32; 4]>,
    /// STEP holds a value until the next key; LINEAR (and CUBICSPLINE,
    /// whose keys' values are read and joined linearly) blend.
    pub step: bool,
}

/// One channel of morph target weights (glTF 2.0 §3.11: a node's
/// `weights` path): per keyframe, one weight per target of its mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct MorphChannel {
    pub node: usize,
    pub times: Vec<f32>,
    /// Keyframe-major: `targets` weights per keyframe.
    pub values: Vec<f32>,
    pub targets: usize,
    pub step: bool,
}

impl MorphChannel {
    /// The weights at `t` into `out` (held before the first key and after
    /// the last, stepped or blended between).
    pub fn weights_at(&self, t: f32, out: &mut [f32]) {
        let n = self.targets;
        let key = |k: usize| &self.values[k * n..(k + 1) * n];
        let after = self.times.partition_point(|&k| k <= t);
        let (a, b, f) = if after == 0 {
            (key(0), key(0), 0.0)
        } else if after >= self.times.len() || self.step {
            (key(after - 1), key(after - 1), 0.0)
        } else {
            let (t0, t1) = (self.times[after - 1], self.times[after]);
            let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
            (key(after - 1), key(after), f)
        };
        for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
            *o = x + (y - x) * f;
        }
    }
}

/// One animation: its channels that move nodes, and those that weigh
/// their meshes' morph targets.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    pub name: Option<String>,
    pub channels: Vec<Channel>,
    pub morphs: Vec<MorphChannel>,
}

impl Animation {
    /// The span of its keyframes.
    pub fn span(&self) -> (f32, f32) {
        let times = || {
            let nodes = self.channels.iter().map(|c| &c.times);
            nodes.chain(self.morphs.iter().map(|c| &c.times))
        };
        let first = times().filter_map(|t| t.first());
        let last = times().filter_map(|t| t.last());
        (
            first.copied().fold(f32::INFINITY, f32::min).min(0.0),
            last.copied().fold(0.0f32, f32::max),
        )
    }
}

/// The scene's rig.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rig {
    pub rest: Vec<Trs>,
    pub parent: Vec<Option<usize>>,
    pub skins: Vec<SkinDef>,
    pub animations: Vec<Animation>,
    /// Per node, its morph target weights at rest (the node's `weights`,
    /// else its mesh's; empty for none).
    pub rest_weights: Vec<Vec<f32>>,
}

/// Reads the rig of `document` from its `buffers`.
pub fn read(document: &gltf::Document, buffers: &[gltf::buffer::Data]) -> ParseResult<Rig> {
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut parent = vec![None; document.nodes().len()];
    let mut rest = Vec::with_capacity(parent.len());
    let mut rest_weights = Vec::with_capacity(parent.len());
    for node in document.nodes() {
        let weights = node
            .weights()
            .or_else(|| node.mesh().and_then(|m| m.weights()));
        rest_weights.push(weights.map_or(Vec::new(), <[f32]>::to_vec));
        for child in node.children() {
            parent[child.index()] = Some(node.index());
        }
        let (t, r, s) = node.transform().decomposed();
        rest.push(Trs {
            translation: Vec3::from_array(t),
            rotation: Quat::from_array(r).normalize(),
            scale: Vec3::from_array(s),
        });
    }
    let mut skins = Vec::new();
    for skin in document.skins() {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(acc) => {
                check_accessor(&acc, buffers)?;
                let read = skin.reader(get).read_inverse_bind_matrices();
                read.map(|m| m.map(|m| Mat4::from_cols_array_2d(&m)).collect())
                    .unwrap_or_default()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        if inverse_bind.len() < joints.len() {
            return Err(ParseError::item(
                format!("skin {}", skin.index()),
                format!("expected {} inverse bind matrices", joints.len()),
            ));
        }
        skins.push(SkinDef {
            joints,
            inverse_bind,
        });
    }
    let mut animations = Vec::new();
    for animation in document.animations() {
        let mut channels = Vec::new();
        let mut morphs = Vec::new();
        for channel in animation.channels() {
            use gltf::animation::Interpolation as I;
            use gltf::animation::Property as P;
            use gltf::animation::util::ReadOutputs as O;
            let sampler = channel.sampler();
            check_accessor(&sampler.input(), buffers)?;
            check_accessor(&sampler.output(), buffers)?;
            let reader = channel.reader(get);
            let times: Vec<f32> = reader
                .read_inputs()
                .map(Iterator::collect)
                .unwrap_or_default();
            let bad = |what: String| {
                ParseError::item(
                    format!(
                        "animation {} channel {}",
                        animation.index(),
                        channel.index()
                    ),
                    what,
                )
            };
            let path = match channel.target().property() {
                P::Translation => Path::Translation,
                P::Rotation => Path::Rotation,
                P::Scale => Path::Scale,
                P::MorphTargetWeights => {
                    let mut values: Vec<f32> = match reader.read_outputs() {
                        Some(O::MorphTargetWeights(w)) => w.into_f32().collect(),
                        _ => Vec::new(),
                    };
                    let cubic = sampler.interpolation() == I::CubicSpline;
                    let per_key = values.len() / times.len().max(1) / if cubic { 3 } else { 1 };
                    if times.is_empty() || per_key == 0 || !values.len().is_multiple_of(times.len())
                    {
                        return Err(bad(format!(
                            "expected the same weights per keyframe, found {} keyframes \
                             and {} weights",
                            times.len(),
                            values.len()
                        )));
                    }
                    if cubic {
                        // In-tangents, values, out-tangents per key: the values.
                        values = (values.chunks_exact(3 * per_key))
                            .flat_map(|c| c[per_key..2 * per_key].to_vec())
                            .collect();
                    }
                    morphs.push(MorphChannel {
                        node: channel.target().node().index(),
                        times,
                        values,
                        targets: per_key,
                        step: sampler.interpolation() == I::Step,
                    });
                    continue;
                }
            };
            let mut values: Vec<[f32; 4]> = match reader.read_outputs() {
                Some(O::Translations(v)) | Some(O::Scales(v)) => {
                    v.map(|[x, y, z]| [x, y, z, 0.0]).collect()
                }
                Some(O::Rotations(r)) => r.into_f32().collect(),
                _ => Vec::new(),
            };
            if sampler.interpolation() == I::CubicSpline {
                // In-tangent, value, out-tangent per key: the values.
                values = values.chunks_exact(3).map(|c| c[1]).collect();
            }
            if times.is_empty() || values.len() != times.len() {
                return Err(bad(format!(
                    "expected one output per keyframe, found {} keyframes and {} outputs",
                    times.len(),
                    values.len()
                )));
            }
            channels.push(Channel {
                node: channel.target().node().index(),
                path,
                times,
                values,
                step: sampler.interpolation() == I::Step,
            });
        }
        animations.push(Animation {
            name: animation.name().map(str::to_string),
            channels,
            morphs,
        });
    }
    Ok(Rig {
        rest,
        parent,
        skins,
        animations,
        rest_weights,
    })
}
