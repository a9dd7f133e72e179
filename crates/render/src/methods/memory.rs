//! An up-front estimate of a render's peak memory, from what each method allocates (films,
//! tiles, per-band splat layers, per-strategy images, Markov chain states, output buffers),
//! and the check that refuses, before any work, a render that does not fit.
//!
//! The figures are allocations, not touched pages: zeroed buffers the kernel maps lazily
//! still count, since an address-space limit counts them. Per-chain sizes were measured
//! (peak RSS over chain counts, Cornell box) and rounded up by about a quarter; they are
//! estimates, not bounds.

use mcmc_core::render_loop::EXACT_GRID_BYTES_PER_PIXEL;

use super::{
    DrmltSettings, IntegratorKind, MalaSettings, MethodSettings, MmltSettings, RenderSettings,
};
use crate::bdpt::MAX_PATH_DEPTH;
use crate::budget::Budget;
/// Byte counts as people read them (`12.34 GiB`), defined with the error that prints them.
pub use crate::error::Bytes;
use crate::error::RenderError;
use crate::mlt::dr::{DrBase, DrVariant};
use crate::mlt::mala::MalaVariant;
use crate::scene::Scene;

/// The environment variable that overrides the available memory (bytes; for tests and for
/// machines whose limit the process cannot see, such as a container's).
pub const MEMORY_LIMIT_VAR: &str = "CHAINLIGHT_MEMORY_LIMIT";

/// Bytes per pixel of one exact splat layer (`mcmc_core::render_loop::ExactSplatGrid`): the
/// Markov chain methods' one film shared by all chains (delayed-rejection MLT with its stage
/// map: two), BDPT's light-tracing layer, LQMC's sums.
const EXACT_GRID: u64 = EXACT_GRID_BYTES_PER_PIXEL as u64;
/// Bytes per pixel of an f32 RGB image.
const IMAGE: u64 = 12;
/// Writing the EXR and the PNG preview: the tonemapped bytes and the encoders' buffers.
const OUTPUT: u64 = 8;
/// A film of weighted pixel sums (`render::film::Film`).
const FILM: u64 = 32;
/// The f64 splat layer a film allocates when splats are merged into it.
const FILM_SPLATS: u64 = 24;
/// A tile of weighted pixel sums (`render::film::FilmTile`).
const FILM_TILE: u64 = 32;
/// LQMC's sparse per-tile splat sums (pixel index and f64 RGB), held for a whole pass:
/// measured about this much per pixel at one sample per pixel, rounded up.
const LQMC_TILES: u64 = 64;
/// Stack of a worker thread.
const THREAD_STACK: u64 = 2 << 20;
/// A triangle of a scene copy (mesh, BVH, light distribution).
const TRIANGLE: u64 = 256;
/// A texel of a scene copy.
const TEXEL: u64 = 16;

/// What a render is estimated to need at its peak, by part.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// Films, tiles, splat layers, per-strategy images and output buffers: what grows with
    /// the image.
    pub image_bytes: u64,
    /// The Markov chains' states (`chains` times `bytes_per_chain`).
    pub chain_bytes: u64,
    /// Chains the render would start (capped at the mutations under a sample budget).
    pub chains: u64,
    /// Estimated bytes of one chain.
    pub bytes_per_chain: u64,
    /// A copy of the scene (made when the method renders through a camera of another size)
    /// and the worker threads' stacks.
    pub fixed_bytes: u64,
}

impl MemoryEstimate {
    /// The estimated peak in bytes.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.image_bytes
            .saturating_add(self.chain_bytes)
            .saturating_add(self.fixed_bytes)
    }
}

/// Estimates the peak memory of rendering `scene` with `settings`.
#[must_use]
pub fn estimate(settings: &RenderSettings, scene: &Scene) -> MemoryEstimate {
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let depth = settings.max_depth.min(MAX_PATH_DEPTH);
    let image_bytes = image_bytes(settings, depth).saturating_add(pixels.saturating_mul(OUTPUT));
    let bytes_per_chain = chain_bytes(&settings.method, depth);
    let chains = match (requested_chains(&settings.method), settings.budget) {
        (0, _) => 0,
        (c, Budget::SamplesPerPixel(n)) => (c as u64).min(pixels.saturating_mul(u64::from(n))),
        (c, Budget::Time(_)) => c as u64,
    };
    let method = settings.method.method();
    let camera = scene.camera();
    let copies_scene = method.sized_camera()
        && (camera.width(), camera.height()) != (settings.width, settings.height);
    let scene_copy = if copies_scene {
        let texels: u64 = scene
            .textures()
            .iter()
            .map(|t| (t.width() * t.height()) as u64)
            .sum();
        (scene.mesh().triangle_count() as u64)
            .saturating_mul(TRIANGLE)
            .saturating_add(texels.saturating_mul(TEXEL))
    } else {
        0
    };
    MemoryEstimate {
        image_bytes,
        chain_bytes: chains.saturating_mul(bytes_per_chain),
        chains,
        bytes_per_chain,
        fixed_bytes: scene_copy
            .saturating_add((settings.threads as u64).saturating_mul(THREAD_STACK)),
    }
}

/// Bytes that grow with the image: the method's buffers at its peak plus the final image.
fn image_bytes(settings: &RenderSettings, depth: u32) -> u64 {
    let (w, h) = (u64::from(settings.width), u64::from(settings.height));
    let px = w * h;
    let per_pixel = |bytes: u64| px.saturating_mul(bytes);
    let mcmc = |layers: u64| per_pixel(layers * EXACT_GRID + IMAGE);
    match &settings.method {
        // Film, the tiles of a pass (held until the pass is merged), the image.
        MethodSettings::Pt(_) | MethodSettings::Qmc(_) => per_pixel(FILM + FILM_TILE + IMAGE),
        MethodSettings::Bdpt(s) => {
            let mut bytes = per_pixel(bdpt_bytes_per_pixel());
            if s.strategy_images {
                let d = u64::from(depth);
                let (camera, light) = ((d + 1) * (d + 2) / 2, d);
                // Per camera strategy its tiles and its image; per light strategy its splat
                // layer and its image.
                let per = camera * (FILM_TILE + IMAGE) + light * (EXACT_GRID + IMAGE);
                bytes = bytes.saturating_add(per_pixel(per));
            }
            bytes
        }
        // The direct-lighting pass (BDPT) runs first; its image stays while the chains run.
        MethodSettings::Pssmlt(s) => {
            let chains = mcmc(1).saturating_add(per_pixel(IMAGE));
            if s.direct.applies_to(settings.max_depth, s.pass_depth()) {
                chains.max(per_pixel(bdpt_bytes_per_pixel()))
            } else {
                chains
            }
        }
        MethodSettings::Mmlt(MmltSettings { direct, .. })
        | MethodSettings::Mala(MalaSettings { direct, .. }) => {
            let pass = direct
                .pass
                .applies_to(settings.max_depth, direct.pass_depth());
            with_direct_pass(mcmc(1), pass, per_pixel)
        }
        // Two layers (image and stage 2) and the stage map image.
        MethodSettings::Drmlt(_) => mcmc(2).saturating_add(per_pixel(IMAGE + OUTPUT)),
        // Plus the per-pixel scale map of regional adaptation.
        MethodSettings::PathMlt(_) => mcmc(1).saturating_add(per_pixel(8)),
        // The sums, a partial first progression, the per-tile splats of a pass, the image.
        MethodSettings::Lqmc(_) => per_pixel(2 * EXACT_GRID + LQMC_TILES + IMAGE),
    }
}

/// A chain method's peak with a direct-lighting pass (BDPT, run first; its image stays while
/// the chains run) if `pass`.
fn with_direct_pass(chains: u64, pass: bool, per_pixel: impl Fn(u64) -> u64) -> u64 {
    if pass {
        chains
            .saturating_add(per_pixel(IMAGE))
            .max(per_pixel(bdpt_bytes_per_pixel()))
    } else {
        chains
    }
}

/// BDPT without strategy images: the camera tiles of the bands (together one image of
/// tiles), the shared light-tracing layer, then the merge film with its splat layer and the
/// image.
const fn bdpt_bytes_per_pixel() -> u64 {
    FILM_TILE + EXACT_GRID + FILM + FILM_SPLATS + IMAGE
}

/// The chain count of a Markov chain method's settings (0 for the others).
fn requested_chains(method: &MethodSettings) -> usize {
    match method {
        MethodSettings::Pssmlt(s) => s.chain.chains,
        MethodSettings::Mmlt(s) => s.chain.chains,
        MethodSettings::Drmlt(s) => s.chain.chains,
        MethodSettings::Mala(s) => s.chain.chains,
        MethodSettings::PathMlt(s) => s.chains,
        _ => 0,
    }
}

/// Measured bytes of one chain (its state, its proposal's, their payloads and subpath
/// scratch, its kernel and controller), rounded up, at path depth `depth`.
fn chain_bytes(method: &MethodSettings, depth: u32) -> u64 {
    const KIB: u64 = 1024;
    let d = u64::from(depth);
    match method {
        // The primary sample vector and both BDPT subpaths grow with the depth.
        MethodSettings::Pssmlt(_) => 9 * KIB + 1536 * d,
        MethodSettings::Drmlt(DrmltSettings { variant, on, .. }) => match (variant, on) {
            (DrVariant::CheapThenExpensive, _) => 12 * KIB,
            (_, DrBase::Mmlt) => 20 * KIB + 128 * d,
            (_, DrBase::Pssmlt | DrBase::PssmltPt) => 8 * KIB + 3 * KIB * d,
        },
        // One depth per chain, most of them shallow.
        MethodSettings::Mmlt(_) => 8 * KIB + 64 * d,
        MethodSettings::Mala(MalaSettings { config, .. }) => match config.variant {
            MalaVariant::Plain | MalaVariant::Online => 11 * KIB + 64 * d,
            MalaVariant::Cache | MalaVariant::Hybrid => 50 * KIB + 64 * d,
        },
        MethodSettings::PathMlt(_) => 2 * KIB + 32 * d,
        _ => 0,
    }
}

/// Where the memory limit came from and how many bytes it leaves.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Available {
    /// Bytes available to the render.
    pub bytes: u64,
    /// What limits it (`MemAvailable in /proc/meminfo`, the address-space limit, or
    /// [`MEMORY_LIMIT_VAR`]).
    pub source: String,
}

/// The memory available to a render: [`MEMORY_LIMIT_VAR`] if set, else the smaller of the
/// system's available memory (`MemAvailable` in `/proc/meminfo`) and what the process's
/// address-space limit leaves (`ulimit -v`). `Ok(None)` where neither can be read.
///
/// # Errors
/// [`RenderError::InvalidSetting`] naming [`MEMORY_LIMIT_VAR`] if it is set but not a number
/// of bytes.
pub fn available() -> Result<Option<Available>, RenderError> {
    if let Some(value) = std::env::var_os(MEMORY_LIMIT_VAR) {
        let text = value.to_string_lossy();
        return match text.trim().parse::<u64>() {
            Ok(bytes) => Ok(Some(Available {
                bytes,
                source: MEMORY_LIMIT_VAR.to_owned(),
            })),
            Err(_) => Err(RenderError::setting(
                MEMORY_LIMIT_VAR,
                text,
                "a number of bytes, e.g. 8000000000",
            )),
        };
    }
    let system = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| kib_field(&text, "MemAvailable:"))
        .map(|bytes| Available {
            bytes,
            source: "MemAvailable in /proc/meminfo".to_owned(),
        });
    let address_space = address_space_left().map(|bytes| Available {
        bytes,
        source: "the address-space limit (ulimit -v)".to_owned(),
    });
    Ok(match (system, address_space) {
        (Some(a), Some(b)) => Some(if b.bytes < a.bytes { b } else { a }),
        (a, b) => a.or(b),
    })
}

/// A `Name:   123 kB` line of a `/proc` file, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// The soft address-space limit minus the address space in use, if there is a limit.
fn address_space_left() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = kib_field(&status, "VmSize:").unwrap_or(0);
    Some(soft.saturating_sub(used))
}

/// Refuses, before any work, a render whose estimated peak exceeds the available memory
/// ([`available`]), with the estimate, the limit and the flags that would make it fit.
///
/// # Errors
/// [`RenderError::OutOfMemory`]; [`RenderError::InvalidSetting`] for a malformed
/// [`MEMORY_LIMIT_VAR`].
pub fn check(settings: &RenderSettings, scene: &Scene) -> Result<MemoryEstimate, RenderError> {
    let need = estimate(settings, scene);
    let Some(available) = available()? else {
        return Ok(need);
    };
    if need.total() <= available.bytes {
        return Ok(need);
    }
    Err(RenderError::OutOfMemory {
        needed: need.total(),
        available: available.bytes,
        limit: available.source,
        advice: advice(settings, scene, &need, available.bytes),
    })
}

/// What would fit: the largest image of the same aspect, and the most chains.
fn advice(settings: &RenderSettings, scene: &Scene, need: &MemoryEstimate, bytes: u64) -> String {
    let mut parts = Vec::new();
    let (w, h) = (settings.width, settings.height);
    // The largest scale of both sides that fits (bisection: the estimate is monotonic).
    let fits = |s: &RenderSettings| estimate(s, scene).total() <= bytes;
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        let scaled = RenderSettings {
            width: ((f64::from(w) * mid) as u32).max(1),
            height: ((f64::from(h) * mid) as u32).max(1),
            ..settings.clone()
        };
        if fits(&scaled) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (fw, fh) = ((f64::from(w) * lo) as u32, (f64::from(h) * lo) as u32);
    if fw >= 1 && fh >= 1 {
        parts.push(format!("--width/--height of at most about {fw}x{fh}"));
    }
    let image_part = need.image_bytes.saturating_add(need.fixed_bytes);
    if need.chains > 0 && need.bytes_per_chain > 0 {
        let spare = bytes.saturating_sub(image_part);
        let most = (spare / need.bytes_per_chain).min(need.chains);
        if most >= 1 {
            parts.push(format!("--chains of at most {most}"));
        }
    }
    if let MethodSettings::Bdpt(b) = &settings.method {
        if b.strategy_images {
            parts.push("no --strategy-images".to_owned());
        }
    }
    let kind: IntegratorKind = settings.method.kind();
    let breakdown = format!(
        "{} for the image buffers of {} at {w}x{h}{}",
        Bytes(need.image_bytes),
        kind.name(),
        if need.chains > 0 {
            format!(
                ", {} for {} chains ({} each)",
                Bytes(need.chain_bytes),
                need.chains,
                Bytes(need.bytes_per_chain)
            )
        } else {
            String::new()
        }
    );
    if parts.is_empty() {
        format!("{breakdown}; even the smallest render does not fit")
    } else {
        format!("{breakdown}; it fits with {}", parts.join(", or "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::{BdptSettings, PssmltSettings};

    fn settings(kind: IntegratorKind, side: u32) -> RenderSettings {
        RenderSettings {
            width: side,
            height: side,
            method: kind.settings(),
            ..RenderSettings::default()
        }
    }

    #[test]
    fn the_estimate_grows_with_the_image_and_the_chains() {
        let scene = Scene::cornell_box(64, 64);
        for info in crate::INTEGRATORS {
            let small = estimate(&settings(info.kind, 256), &scene).total();
            let large = estimate(&settings(info.kind, 1024), &scene).total();
            assert!(large > 4 * small / 2, "{}: {small} -> {large}", info.name);
            // At least the image itself, at most a few KiB per pixel at 1024 x 1024.
            assert!(large >= 1024 * 1024 * IMAGE, "{}: {large}", info.name);
            assert!(large < 1024 * 1024 * 4096, "{}: {large}", info.name);
        }
        let mut few = settings(IntegratorKind::Pssmlt, 256);
        let mut many = few.clone();
        few.method.set_chains(100, 1000);
        many.method.set_chains(100_000, 1000);
        let (few, many) = (estimate(&few, &scene), estimate(&many, &scene));
        assert_eq!((few.chains, many.chains), (100, 100_000));
        assert!(many.total() > few.total() + 99_000 * few.bytes_per_chain / 2);
        // Chains beyond the mutations are not started.
        let mut capped = settings(IntegratorKind::Mmlt, 16);
        capped.budget = Budget::SamplesPerPixel(1);
        capped.method.set_chains(1_000_000, 1000);
        assert_eq!(estimate(&capped, &scene).chains, 256);
    }

    #[test]
    fn deeper_paths_and_strategy_images_cost_more() {
        let scene = Scene::cornell_box(64, 64);
        let mut shallow = settings(IntegratorKind::Pssmlt, 64);
        shallow.method = PssmltSettings::default().into();
        let deep = RenderSettings {
            max_depth: 62,
            ..shallow.clone()
        };
        assert!(
            estimate(&deep, &scene).bytes_per_chain
                > 4 * estimate(&shallow, &scene).bytes_per_chain
        );
        // Depths beyond BDPT's limit are not rendered: they cost nothing more.
        let deeper = RenderSettings {
            max_depth: 1024,
            ..deep.clone()
        };
        assert_eq!(estimate(&deeper, &scene), estimate(&deep, &scene));
        let plain = settings(IntegratorKind::Bdpt, 256);
        let mut strategies = plain.clone();
        strategies.method = BdptSettings {
            strategy_images: true,
            ..BdptSettings::default()
        }
        .into();
        assert!(estimate(&strategies, &scene).total() > 4 * estimate(&plain, &scene).total());
    }

    #[test]
    fn proc_fields_parse() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   2048 kB\n";
        assert_eq!(kib_field(text, "MemAvailable:"), Some(2048 * 1024));
        assert_eq!(kib_field(text, "Nope:"), None);
        assert_eq!(Bytes(3 << 30).to_string(), "3.00 GiB");
        assert_eq!(Bytes(5 << 20).to_string(), "5 MiB");
    }
}
