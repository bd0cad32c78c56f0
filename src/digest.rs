//! A small, stable 64-bit digest for fingerprints and checksums of files this program writes and reads
//! back on other machines (so it cannot be std's `DefaultHasher`, whose algorithm may change between
//! Rust releases).
//!
//! Each 64-bit word is folded in by `h ← mix(h ⊕ w)`, where `mix` is SplitMix64's finaliser (Steele,
//! Lea, Flood 2014). `mix` is a bijection, so for a fixed input every step is a bijection of the state:
//! two inputs that differ in a single word (one flipped bit, say) always give different digests, and
//! otherwise unrelated inputs collide with probability about 2⁻⁶⁴. The length is folded in last, so a
//! truncated input differs from the whole one too. Not cryptographic: it guards against accidents
//! (a corrupt file, a part of another scene), not against forgery.

/// SplitMix64's increment, the golden ratio's fraction (Steele, Lea, Flood 2014).
pub const SPLITMIX_STEP: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's finaliser: a bijective 64-bit mix with full avalanche.
#[inline]
pub fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A running digest over bytes, words and floats.
#[derive(Clone, Debug)]
pub struct Digest {
    state: u64,
    len: u64,
}

impl Default for Digest {
    fn default() -> Self {
        Digest::new()
    }
}

impl Digest {
    /// An empty digest.
    pub fn new() -> Self {
        // Any non-zero start will do.
        Digest {
            state: SPLITMIX_STEP,
            len: 0,
        }
    }

    /// Folds in one 64-bit word.
    #[inline]
    pub fn word(&mut self, w: u64) {
        self.state = mix(self.state ^ w);
        self.len += 8;
    }

    /// Folds in bytes, eight at a time (the last word zero-padded; the length tells the padding apart).
    pub fn bytes(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.word(u64::from_le_bytes(c.try_into().expect("eight bytes")));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut last = [0u8; 8];
            last[..rest.len()].copy_from_slice(rest);
            self.word(u64::from_le_bytes(last));
            self.len -= (8 - rest.len()) as u64;
        }
    }

    /// Folds in floats by their bit patterns (so 0.0 and -0.0 differ, as they may render differently).
    pub fn floats(&mut self, values: &[f32]) {
        let mut pairs = values.chunks_exact(2);
        for p in &mut pairs {
            self.word(u64::from(p[0].to_bits()) | u64::from(p[1].to_bits()) << 32);
        }
        if let [v] = pairs.remainder() {
            self.word(u64::from(v.to_bits()));
            self.len -= 4;
        }
    }

    /// Folds in 32-bit integers.
    pub fn u32s(&mut self, values: &[u32]) {
        let mut pairs = values.chunks_exact(2);
        for p in &mut pairs {
            self.word(u64::from(p[0]) | u64::from(p[1]) << 32);
        }
        if let [v] = pairs.remainder() {
            self.word(u64::from(*v));
            self.len -= 4;
        }
    }

    /// The digest of everything folded in so far.
    pub fn finish(&self) -> u64 {
        mix(self.state ^ mix(self.len))
    }
}

/// The digest of `bytes`.
pub fn of_bytes(bytes: &[u8]) -> u64 {
    let mut d = Digest::new();
    d.bytes(bytes);
    d.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_single_bit_flip_changes_the_digest() {
        let data: Vec<u8> = (0..61u32).map(|i| (i * 37 % 251) as u8).collect();
        let base = of_bytes(&data);
        for byte in 0..data.len() {
            for bit in 0..8 {
                let mut flipped = data.clone();
                flipped[byte] ^= 1 << bit;
                assert_ne!(of_bytes(&flipped), base, "byte {byte} bit {bit}");
            }
        }
    }

    #[test]
    fn lengths_and_padding_are_told_apart() {
        assert_ne!(of_bytes(b"abc"), of_bytes(b"abc\0"));
        assert_ne!(of_bytes(b""), of_bytes(b"\0"));
        let mut a = Digest::new();
        a.floats(&[1.0]);
        let mut b = Digest::new();
        b.floats(&[1.0, 0.0]);
        assert_ne!(a.finish(), b.finish());
        // Pinned: digests are written into files read by other builds, so the algorithm must not
        // change (this value was computed independently, in Python).
        assert_eq!(of_bytes(b"whitted"), 0xffc3_2af5_96e4_3d59);
    }
}
