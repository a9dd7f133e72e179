//! Stateless integer hashing: a 64-bit mixer and Kensler's hashed permutation.

/// The SplitMix64 / `murmur3` style finaliser: a bijective avalanche mix of 64 bits.
#[inline]
pub(crate) fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 31;
    x
}

/// Hashes several words into one (order matters).
#[inline]
pub(crate) fn hash_words(words: &[u64]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15_u64;
    for &w in words {
        h = mix64(h ^ mix64(w.wrapping_add(0x9e37_79b9_7f4a_7c15)));
    }
    h
}

/// A uniform number in `[0, 1)` from the top 53 bits of a hash.
#[inline]
pub(crate) fn unit_f64(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Kensler's hashed permutation ("Correlated Multi-Jittered Sampling", Pixar 2013, listing 3):
/// the image of `i` under a pseudo-random permutation of `0..len` chosen by `key`.
///
/// A bijection on the next power of two, restricted to `0..len` by cycle walking; no storage.
#[inline]
pub(crate) fn permute(mut i: u32, len: u32, key: u32) -> u32 {
    debug_assert!(len > 0 && i < len);
    let p = key;
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            break;
        }
    }
    ((i as u64 + p as u64) % len as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_bijection() {
        for len in [1u32, 2, 3, 5, 7, 16, 17, 100, 1619] {
            for key in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, key);
                    assert!(j < len);
                    assert!(!seen[j as usize], "len {len} key {key}: {j} twice");
                    seen[j as usize] = true;
                }
            }
        }
    }

    #[test]
    fn unit_f64_is_in_unit_interval() {
        assert_eq!(unit_f64(0), 0.0);
        assert!(unit_f64(u64::MAX) < 1.0);
    }
}
