//! The part file: one shard's accumulators with the metadata that says which render they
//! belong to, and a checksum that catches truncation and corruption.
//!
//! Layout (little-endian): the magic line `chainlight-part 1\n`; a `u64` header length and
//! the header, `key: value` lines; the components, each a kind byte and its arrays (f64
//! pixel sums; a fraction-bit count and 128-bit fixed-point splat sums; the counts); the
//! FNV-1a 64 hash of every byte before it.

use std::io::Read;
use std::path::Path;

use mcmc_core::render_loop::{
    ExactSplatGrid, LargeStepSums, Normalization, NormalizationMode, Shard,
};

use super::{Component, Partial};

/// The file extension of part files.
pub const PART_EXTENSION: &str = "clpart";

const MAGIC: &[u8] = b"chainlight-part 2\n";

/// Most targets (MMLT depths) a part's normalisation may hold.
const MAX_TARGETS: u64 = 1024;

/// Most jobs a part's normalisation may hold (the render loop's limit).
const MAX_JOBS: u64 = 4096;
/// Largest accepted image side in a part (the render's own limit).
const MAX_SIDE: usize = 16_384;
/// Largest accepted header.
const MAX_HEADER: u64 = 1 << 20;

/// What a part says about the render it belongs to. Parts merge only if everything but
/// `shard.index` is equal.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartHeader {
    /// The integrator's name.
    pub integrator: String,
    /// Every render setting except the thread count and the shard, as text.
    pub settings: String,
    /// The scene's identity (a hash of the scene file and of the options that change it).
    pub scene: String,
    /// The master seed.
    pub seed: u64,
    /// The sample budget (`--spp N` or `--time S`).
    pub budget: String,
    /// Which shard this is.
    pub shard: Shard,
}

impl PartHeader {
    fn to_text(&self) -> String {
        format!(
            "integrator: {}\nsettings: {}\nscene: {}\nseed: {}\nbudget: {}\nshard: {}/{}\n",
            self.integrator,
            one_line(&self.settings),
            self.scene,
            self.seed,
            self.budget,
            self.shard.index,
            self.shard.count
        )
    }

    fn from_text(text: &str) -> Result<Self, String> {
        let field = |key: &str| -> Result<&str, String> {
            text.lines()
                .find_map(|l| l.strip_prefix(key).and_then(|r| r.strip_prefix(": ")))
                .ok_or_else(|| format!("the header has no '{key}'"))
        };
        let (index, count) = field("shard")?
            .split_once('/')
            .and_then(|(k, n)| Some((k.parse().ok()?, n.parse().ok()?)))
            .ok_or("the header's shard is not K/N")?;
        Ok(Self {
            integrator: field("integrator")?.to_owned(),
            settings: field("settings")?.to_owned(),
            scene: field("scene")?.to_owned(),
            seed: field("seed")?.parse().map_err(|_| "the header's seed")?,
            budget: field("budget")?.to_owned(),
            shard: Shard { index, count },
        })
    }

    /// The first field that differs from `other` other than the shard index, as
    /// `(name, this value, other value)`.
    #[must_use]
    pub fn difference(&self, other: &PartHeader) -> Option<(&'static str, String, String)> {
        let pairs = [
            ("integrator", &self.integrator, &other.integrator),
            ("settings", &self.settings, &other.settings),
            ("scene", &self.scene, &other.scene),
            ("budget", &self.budget, &other.budget),
        ];
        if self.seed != other.seed {
            return Some(("seed", self.seed.to_string(), other.seed.to_string()));
        }
        if self.shard.count != other.shard.count {
            return Some((
                "shard count",
                self.shard.count.to_string(),
                other.shard.count.to_string(),
            ));
        }
        pairs
            .into_iter()
            .find(|(_, a, b)| a != b)
            .map(|(name, a, b)| (name, a.clone(), b.clone()))
    }
}

/// A short hexadecimal fingerprint of `bytes` (FNV-1a 64): for recording which scene file a
/// part was rendered from. Not a cryptographic hash.
#[must_use]
pub fn fingerprint(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a(bytes))
}

fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// FNV-1a, 64 bits: the part's checksum, and a cheap identity of a scene file's bytes
/// ([`fingerprint`]).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Writes `partial` with `header` to `path` (atomically: `crate::files::write_bytes_atomic`;
/// an interrupted write never leaves a truncated part).
///
/// # Errors
/// The I/O error, with the path.
pub fn write_part(path: &Path, header: &PartHeader, partial: &Partial) -> Result<(), String> {
    let mut buf = Vec::new();
    buf.extend_from_slice(MAGIC);
    let text = header.to_text();
    buf.extend_from_slice(&(text.len() as u64).to_le_bytes());
    buf.extend_from_slice(text.as_bytes());
    buf.extend_from_slice(&(partial.width as u64).to_le_bytes());
    buf.extend_from_slice(&(partial.height as u64).to_le_bytes());
    buf.extend_from_slice(&(partial.components.len() as u64).to_le_bytes());
    for c in &partial.components {
        match c {
            Component::Film {
                sum,
                weight,
                light,
                light_samples,
            } => {
                buf.push(0);
                for px in sum {
                    for v in px {
                        buf.extend_from_slice(&v.to_le_bytes());
                    }
                }
                for w in weight {
                    buf.extend_from_slice(&w.to_le_bytes());
                }
                match light {
                    Some(grid) => {
                        buf.push(1);
                        put_grid(&mut buf, grid);
                    }
                    None => buf.push(0),
                }
                buf.extend_from_slice(&light_samples.to_le_bytes());
            }
            Component::Chains {
                grid,
                normalization,
                mutations,
            } => {
                buf.push(1);
                put_grid(&mut buf, grid);
                put_normalization(&mut buf, normalization);
                buf.extend_from_slice(&mutations.to_le_bytes());
            }
            Component::Mean { grid, divisor } => {
                buf.push(2);
                put_grid(&mut buf, grid);
                buf.extend_from_slice(&u64::from(*divisor).to_le_bytes());
            }
        }
    }
    let hash = fnv1a(&buf);
    buf.extend_from_slice(&hash.to_le_bytes());
    crate::files::write_bytes_atomic(path, &buf)
        .map_err(|e| format!("cannot write part '{}': {e}", path.display()))?;
    Ok(())
}

fn put_grid(buf: &mut Vec<u8>, grid: &ExactSplatGrid) {
    buf.extend_from_slice(&u64::from(grid.fraction_bits()).to_le_bytes());
    for i in 0..grid.width() * grid.height() {
        for v in grid.raw(i) {
            buf.extend_from_slice(&v.to_le_bytes());
        }
    }
}

/// The normalisation's mode, bootstrap and per-job large-step sums (every `f64` by its bits).
fn put_normalization(buf: &mut Vec<u8>, n: &Normalization) {
    match n.mode {
        NormalizationMode::Pooled => buf.push(0),
        NormalizationMode::Bootstrap => buf.push(1),
        NormalizationMode::Given(b) => {
            buf.push(2);
            buf.extend_from_slice(&b.to_le_bytes());
        }
    }
    buf.extend_from_slice(&(n.targets() as u64).to_le_bytes());
    buf.extend_from_slice(&(n.jobs as u64).to_le_bytes());
    for d in 0..n.targets() {
        buf.extend_from_slice(&n.bootstrap_b[d].to_le_bytes());
        buf.extend_from_slice(&n.bootstrap_variance[d].to_le_bytes());
        buf.extend_from_slice(&n.bootstrap_samples[d].to_le_bytes());
    }
    buf.extend_from_slice(&n.bootstrap_standard_error.to_le_bytes());
    for s in &n.large_steps {
        buf.extend_from_slice(&s.count.to_le_bytes());
        buf.extend_from_slice(&s.sum.to_le_bytes());
        buf.extend_from_slice(&s.sum_sq.to_le_bytes());
    }
}

/// A cursor over a part's bytes that turns every short read into an error.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or("truncated (the file ends inside its data)")?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or([0; 8]),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn grid(&mut self, width: usize, height: usize) -> Result<ExactSplatGrid, String> {
        let bits = self.u64()?;
        if bits > 120 {
            return Err(format!("bad splat-grid resolution {bits}"));
        }
        let grid = ExactSplatGrid::with_fraction_bits(width, height, bits as u32);
        let n = width * height;
        self.check_left(n * 48)?;
        for i in 0..n {
            let mut v = [0i128; 3];
            for x in &mut v {
                *x = i128::from_le_bytes(self.take(16)?.try_into().unwrap_or([0; 16]));
            }
            grid.add_raw(i, v);
        }
        Ok(grid)
    }
    fn normalization(&mut self) -> Result<Normalization, String> {
        let mode = match self.u8()? {
            0 => NormalizationMode::Pooled,
            1 => NormalizationMode::Bootstrap,
            2 => NormalizationMode::Given(self.f64()?),
            k => return Err(format!("unknown normalisation mode {k}")),
        };
        let (targets, jobs) = (self.u64()?, self.u64()?);
        if targets > MAX_TARGETS || jobs > MAX_JOBS {
            return Err(format!(
                "normalisation of {targets} targets and {jobs} jobs"
            ));
        }
        let (targets, jobs) = (targets as usize, jobs as usize);
        self.check_left(targets * 24 + 8 + targets * jobs * 24)?;
        let (mut b, mut variance, mut samples) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..targets {
            b.push(self.f64()?);
            variance.push(self.f64()?);
            samples.push(self.u64()?);
        }
        let mut n = Normalization::new(mode, b, variance, samples, self.f64()?, jobs);
        for s in &mut n.large_steps {
            *s = LargeStepSums {
                count: self.u64()?,
                sum: self.f64()?,
                sum_sq: self.f64()?,
            };
        }
        Ok(n)
    }

    fn check_left(&self, n: usize) -> Result<(), String> {
        if self.bytes.len() - self.at < n {
            Err("truncated (the file ends inside its data)".into())
        } else {
            Ok(())
        }
    }
}

/// Reads a part file written by [`write_part`].
///
/// # Errors
/// A message naming the file and what is wrong: not a part file, truncated, corrupt (the
/// checksum), a size out of range. Only regular files are read.
pub fn read_part(path: &Path) -> Result<(PartHeader, Partial), String> {
    let fail = |why: String| format!("part '{}': {why}", path.display());
    let file = crate::files::open_regular(path).map_err(|e| fail(e.to_string()))?;
    let len = file.metadata().map_err(|e| fail(e.to_string()))?.len();
    let limit = 64 + MAX_HEADER + (MAX_SIDE * MAX_SIDE * 4 * 8) as u64 * 4;
    if len > limit {
        return Err(fail(format!("{len} bytes is larger than any part")));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit)
        .read_to_end(&mut bytes)
        .map_err(|e| fail(e.to_string()))?;
    parse(&bytes).map_err(fail)
}

fn parse(bytes: &[u8]) -> Result<(PartHeader, Partial), String> {
    if !bytes.starts_with(MAGIC) {
        return Err("not a chainlight part file".into());
    }
    if bytes.len() < MAGIC.len() + 8 {
        return Err("truncated (shorter than its checksum)".into());
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().unwrap_or([0; 8]));
    if fnv1a(body) != stored {
        return Err("truncated or corrupt (the checksum does not match)".into());
    }
    let mut r = Reader {
        bytes: body,
        at: MAGIC.len(),
    };
    let header_len = r.u64()?;
    if header_len > MAX_HEADER {
        return Err("header too large".into());
    }
    let text = std::str::from_utf8(r.take(header_len as usize)?)
        .map_err(|_| "the header is not UTF-8".to_owned())?;
    let header = PartHeader::from_text(text)?;
    let (width, height) = (r.u64()? as usize, r.u64()? as usize);
    if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
        return Err(format!("image size {width}x{height} out of range"));
    }
    let n = width * height;
    let count = r.u64()?;
    if count > 16 {
        return Err(format!("{count} components"));
    }
    let mut components = Vec::new();
    for _ in 0..count {
        let component = match r.u8()? {
            0 => {
                r.check_left(n * 32)?;
                let mut sum = Vec::with_capacity(n);
                for _ in 0..n {
                    sum.push([r.f64()?, r.f64()?, r.f64()?]);
                }
                let mut weight = Vec::with_capacity(n);
                for _ in 0..n {
                    weight.push(r.f64()?);
                }
                let light = match r.u8()? {
                    0 => None,
                    _ => Some(r.grid(width, height)?),
                };
                Component::Film {
                    sum,
                    weight,
                    light,
                    light_samples: r.u64()?,
                }
            }
            1 => Component::Chains {
                grid: r.grid(width, height)?,
                normalization: r.normalization()?,
                mutations: r.u64()?,
            },
            2 => {
                let grid = r.grid(width, height)?;
                let divisor = u32::try_from(r.u64()?).map_err(|_| "bad divisor".to_owned())?;
                Component::Mean { grid, divisor }
            }
            k => return Err(format!("unknown component kind {k}")),
        };
        components.push(component);
    }
    if r.at != body.len() {
        return Err("trailing bytes after the components".into());
    }
    Ok((
        header,
        Partial {
            width,
            height,
            components,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (PartHeader, Partial) {
        let grid = ExactSplatGrid::new(2, 1);
        grid.add_rgb([0.5, 0.5], [1.0, 2.0, 3.0], 0.25);
        (
            PartHeader {
                integrator: "pssmlt".into(),
                settings: "S {\n a: 1 }".into(),
                scene: "abc".into(),
                seed: 7,
                budget: "--spp 4".into(),
                shard: Shard { index: 1, count: 4 },
            },
            Partial {
                width: 2,
                height: 1,
                components: vec![
                    Component::Chains {
                        grid,
                        normalization: {
                            let mut n = Normalization::new(
                                NormalizationMode::Pooled,
                                vec![0.5, 0.25],
                                vec![1e-4, 2e-4],
                                vec![1000, 1000],
                                0.01,
                                3,
                            );
                            n.job_mut(1)[1].push(0.75);
                            n
                        },
                        mutations: 99,
                    },
                    Component::Film {
                        sum: vec![[1.0, 2.0, 3.0], [0.0; 3]],
                        weight: vec![1.0, 0.0],
                        light: None,
                        light_samples: 3,
                    },
                ],
            },
        )
    }

    #[test]
    fn round_trip_and_truncation() {
        let dir = std::env::temp_dir().join(format!("clpart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.clpart");
        let (header, partial) = sample();
        write_part(&path, &header, &partial).unwrap();
        let (h2, p2) = read_part(&path).unwrap();
        assert_eq!(h2.settings, "S {  a: 1 }");
        assert_eq!(h2.shard, header.shard);
        assert_eq!(p2.image().0.pixels, partial.image().0.pixels);
        assert_eq!(
            format!("{:?}", p2.components[0]),
            format!("{:?}", partial.components[0])
        );
        // Truncated by one byte, and one byte flipped: refused, no panic.
        let bytes = std::fs::read(&path).unwrap();
        for bad in [bytes[..bytes.len() - 1].to_vec(), {
            let mut b = bytes.clone();
            b[bytes.len() / 2] ^= 1;
            b
        }] {
            std::fs::write(&path, &bad).unwrap();
            let err = read_part(&path).unwrap_err();
            assert!(
                err.contains("truncated") || err.contains("corrupt"),
                "{err}"
            );
        }
        std::fs::write(&path, b"not a part").unwrap();
        assert!(read_part(&path)
            .unwrap_err()
            .contains("not a chainlight part"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
