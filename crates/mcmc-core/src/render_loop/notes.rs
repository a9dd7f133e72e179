//! The render loop's notes on how far its image can be trusted: targets whose bootstrap
//! found light only a few times, and targets with light that got no chain.

use super::{ChainAllocation, FEW_BOOTSTRAP_HITS};

/// Share of `b` below which a target's weak bootstrap is not worth a note.
const NOTABLE_SHARE: f64 = 0.01;

/// A note if a target carrying at least a hundredth of `b` had fewer than
/// [`FEW_BOOTSTRAP_HITS`] bootstrap samples with light: its `b_d` rests on a handful of
/// samples, so the standard error of `b` (a sample estimate) understates the uncertainty,
/// and light as rare may have been missed entirely.
pub(super) fn few_hits_note(target_b: &[f64], hits: &[u64], b: f64) -> Option<String> {
    if !(b > 0.0 && b.is_finite()) {
        return None;
    }
    let weak: Vec<String> = target_b
        .iter()
        .zip(hits)
        .enumerate()
        .filter(|&(_, (&b_d, &k))| b_d >= NOTABLE_SHARE * b && k < FEW_BOOTSTRAP_HITS)
        .map(|(t, (&b_d, &k))| format!("target {t}: {k} sample(s), {:.0} % of b", 100.0 * b_d / b))
        .collect();
    if weak.is_empty() {
        return None;
    }
    Some(format!(
        "b is uncertain beyond its standard error: {} with light in the bootstrap ({}), fewer than {FEW_BOOTSTRAP_HITS}; light as rare may be missing entirely, so the image may be much too dark or too bright. A larger bootstrap (or more time) makes b reliable",
        if weak.len() == 1 { "a target has few samples" } else { "targets have few samples" },
        weak.join("; ")
    ))
}

/// A note if targets whose bootstrap found light got no chain. Per target
/// ([`ChainAllocation::PerTarget`]) their light is missing from the image; jointly
/// ([`ChainAllocation::Joint`]) the chains that exist carry all of `b`, so the image shows
/// only the light of the targets that got chains, scaled to the whole: right on average over
/// seeds, not in this image. Jointly, a chain count proportional to `b_d` leaves the faintest
/// targets without chains in most renders: noted only when they hold at least a hundredth of
/// `b`.
pub(super) fn missed_targets_note(
    target_b: &[f64],
    target_chains: &[usize],
    allocation: ChainAllocation,
) -> Option<String> {
    let lit = target_b.iter().filter(|&&b_d| b_d > 0.0).count();
    let missed: Vec<usize> = (0..target_b.len())
        .filter(|&t| target_b[t] > 0.0 && target_chains[t] == 0)
        .collect();
    if missed.is_empty() {
        return None;
    }
    let b: f64 = target_b.iter().filter(|b_d| b_d.is_finite()).sum();
    let share: f64 = missed.iter().map(|&t| target_b[t]).sum::<f64>() / b;
    if allocation == ChainAllocation::Joint && (share.is_nan() || share < NOTABLE_SHARE) {
        return None;
    }
    let chains: usize = target_chains.iter().sum();
    let names = if missed.len() <= 8 {
        missed
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    } else {
        format!(
            "{}, {}, ... {}",
            missed[0],
            missed[1],
            missed[missed.len() - 1]
        )
    };
    Some(match allocation {
        ChainAllocation::Joint => format!(
            "{} of {lit} target(s) with light (MMLT: path depths {names}; {:.0} % of b) got no chain of the {chains}: this image shows only the light of the targets that did, scaled to the whole b (right only on average over seeds); use more chains",
            missed.len(),
            100.0 * share
        ),
        _ => format!(
            "{} of {lit} target(s) with light (MMLT: path depths {names}; {:.0} % of b) got no chain ({chains} chains for more targets): their light is missing from the image",
            missed.len(),
            100.0 * share
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_hits_are_noted_only_for_targets_that_matter() {
        assert!(few_hits_note(&[0.5, 0.5], &[100, 30], 1.0).is_none());
        let note = few_hits_note(&[0.5, 0.5], &[100, 3], 1.0).unwrap();
        assert!(note.contains("target 1: 3 sample(s), 50 %"), "{note}");
        // A target with a thousandth of b does not make b uncertain.
        assert!(few_hits_note(&[0.999, 0.001], &[100, 1], 1.0).is_none());
        assert!(few_hits_note(&[0.0, 0.0], &[0, 0], 0.0).is_none());
    }

    #[test]
    fn missed_targets_are_named_with_their_share() {
        assert!(missed_targets_note(&[0.5, 0.5], &[1, 1], ChainAllocation::Joint).is_none());
        // No light, no chain: nothing is missing.
        assert!(missed_targets_note(&[1.0, 0.0], &[2, 0], ChainAllocation::Joint).is_none());
        // Jointly, faint targets without chains are the rule, not worth a note; per target
        // every target with light should have a chain.
        let faint = [0.999, 0.001];
        assert!(missed_targets_note(&faint, &[8, 0], ChainAllocation::Joint).is_none());
        assert!(missed_targets_note(&faint, &[8, 0], ChainAllocation::PerTarget).is_some());
        let joint = missed_targets_note(&[0.75, 0.25], &[1, 0], ChainAllocation::Joint).unwrap();
        assert!(
            joint.contains("1 of 2") && joint.contains("25 % of b"),
            "{joint}"
        );
        assert!(joint.contains("right only on average"), "{joint}");
        let per = missed_targets_note(&[0.75, 0.25], &[1, 0], ChainAllocation::PerTarget).unwrap();
        assert!(per.contains("missing from the image"), "{per}");
    }
}
