//! CRC-32 (IEEE 802.3, reflected polynomial `0xEDB88320`, zlib's `crc32`), the
//! checksum of every section, data block and journal record, computed by `crc32fast`.

/// CRC-32 of `bytes` (the same value as zlib's `crc32`).
///
/// ```
/// assert_eq!(sightline_pvs::crc32(b"123456789"), 0xCBF4_3926);
/// ```
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// Incremental CRC-32, for checksums over several slices.
#[derive(Clone, Debug, Default)]
pub struct Crc32(crc32fast::Hasher);

impl Crc32 {
    pub fn new() -> Self {
        Crc32(crc32fast::Hasher::new())
    }

    pub fn update(mut self, bytes: &[u8]) -> Self {
        self.0.update(bytes);
        self
    }

    pub fn finish(self) -> u32 {
        self.0.finalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table-driven CRC-32 sightline wrote its files with before `crc32fast`: the
    /// new one must give the same bytes.
    fn hand_written(bytes: &[u8]) -> u32 {
        let table: Vec<u32> = (0..256u32)
            .map(|i| {
                (0..8).fold(i, |c, _| {
                    if c & 1 != 0 {
                        0xEDB8_8320 ^ (c >> 1)
                    } else {
                        c >> 1
                    }
                })
            })
            .collect();
        !bytes.iter().fold(0xFFFF_FFFFu32, |c, &b| {
            table[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8)
        })
    }

    #[test]
    fn same_as_the_hand_written_crc_on_sample_data() {
        let seed = include_bytes!("../../../fuzz/seeds/pvs_reader/lyon3.pvs");
        let mut rng = 0x9E37_79B9_7F4A_7C15u64;
        let random: Vec<u8> = (0..100_000)
            .map(|_| {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                rng as u8
            })
            .collect();
        for data in [&seed[..], &random[..], &b""[..], &b"123456789"[..]] {
            for end in [0, 1, 3, 7, 64, 1000, data.len()] {
                let d = &data[..end.min(data.len())];
                assert_eq!(crc32(d), hand_written(d), "{} bytes", d.len());
                let (a, b) = d.split_at(d.len() / 3);
                assert_eq!(Crc32::new().update(a).update(b).finish(), hand_written(d));
            }
        }
    }

    #[test]
    fn the_fuzz_seed_still_reads() {
        // Its section and block checksums were written by the hand-written CRC.
        let seed = include_bytes!("../../../fuzz/seeds/pvs_reader/lyon3.pvs");
        let f = crate::PvsFile::from_bytes(seed.to_vec()).unwrap();
        for i in 0..f.cells().len() {
            f.pvs(i).unwrap();
        }
    }
}
