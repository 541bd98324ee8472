//! Base-colour textures for the viewport, decoded once per image: every cut
//! of a model shares its materials' bytes, so live cuts and previews reuse
//! the decoded texels (and the GPU side the uploaded texture).

use std::sync::{Arc, Mutex, OnceLock, Weak};

use lodstudio_core::geom::Image;

use super::scene::Atlas;

/// Decoded images (or `None`: not decodable) by their shared bytes; an
/// entry goes when the last mesh holding its bytes does.
type Cache = Vec<(Weak<[u8]>, Option<Arc<Atlas>>)>;

static DECODED: Mutex<Cache> = Mutex::new(Vec::new());

/// `image` as texels the viewport uploads; `None` when it cannot be
/// decoded (its material then shows its base colour alone).
pub(super) fn decoded(image: &Image) -> Option<Arc<Atlas>> {
    let mut cache = DECODED.lock().unwrap_or_else(|e| e.into_inner());
    cache.retain(|(bytes, _)| bytes.strong_count() > 0);
    let same = |bytes: &Weak<[u8]>| {
        bytes
            .upgrade()
            .is_some_and(|b| Arc::ptr_eq(&b, &image.bytes))
    };
    if let Some((_, texels)) = cache.iter().find(|(bytes, _)| same(bytes)) {
        return texels.clone();
    }
    let texels = lodstudio_core::io::image::decode_rgba(image)
        .ok()
        .map(|rgba| {
            Arc::new(Atlas {
                width: rgba.width,
                height: rgba.height,
                rgba: rgba.texels,
            })
        });
    cache.push((Arc::downgrade(&image.bytes), texels.clone()));
    texels
}

/// One white texel: the base-colour texture of a material that has a
/// normal map and none of its own (the factor and vertex colours then
/// give its colour alone).
pub(super) fn white() -> Arc<Atlas> {
    static WHITE: OnceLock<Arc<Atlas>> = OnceLock::new();
    WHITE
        .get_or_init(|| {
            Arc::new(Atlas {
                width: 1,
                height: 1,
                rgba: vec![[255; 4]],
            })
        })
        .clone()
}
