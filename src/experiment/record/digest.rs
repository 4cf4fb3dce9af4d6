//! A stable 64-bit digest of bytes (FNV-1a), written as 16 hex digits: ties the shards of one sweep
//! together (`shard::sweep_key`) and names the results a generated report was made from
//! (`report`). Not cryptographic: it detects change, it does not resist forgery. Unlike
//! `std::hash::DefaultHasher` its value never changes between Rust releases, so digests committed in
//! files stay valid.

const OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
const PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a over `parts` in order, each followed by a 0xff byte (no UTF-8 text contains one), so
/// `["ab", "c"]` and `["a", "bc"]` differ.
pub fn digest<'a>(parts: impl IntoIterator<Item = &'a [u8]>) -> String {
    let mut hash = OFFSET_BASIS;
    for part in parts {
        for &byte in part.iter().chain(&[0xff]) {
            hash ^= byte as u64;
            hash = hash.wrapping_mul(PRIME);
        }
    }
    format!("{hash:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_published_fnv1a_vectors_and_separates_parts() {
        // FNV-1a 64 of "a" is 0xaf63dc4c8601ec8c (Fowler–Noll–Vo test vectors); the separator byte
        // makes it the hash of "a\xff".
        let mut h = OFFSET_BASIS;
        for b in b"a" {
            h = (h ^ *b as u64).wrapping_mul(PRIME);
        }
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
        let h = (h ^ 0xff).wrapping_mul(PRIME);
        assert_eq!(digest([b"a".as_slice()]), format!("{h:016x}"));
        assert_ne!(
            digest([b"ab".as_slice(), b"c"]),
            digest([b"a".as_slice(), b"bc"])
        );
        assert_eq!(digest([]), format!("{OFFSET_BASIS:016x}"));
    }
}
