//! The two hashes Alembic files carry, written from their published
//! algorithms: MurmurHash3_x64_128 (Austin Appleby, public domain) digests
//! every stored sample, SpookyHash V2 (Bob Jenkins, public domain) hashes
//! properties and objects. Both read their input as little-endian words.

const MURMUR_C1: u64 = 0x87c3_7b91_1142_53d5;
const MURMUR_C2: u64 = 0x4cf5_ad43_2745_937f;

fn fmix64(mut k: u64) -> u64 {
    k ^= k >> 33;
    k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
    k ^= k >> 33;
    k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    k ^= k >> 33;
    k
}

fn u64_le(bytes: &[u8]) -> u64 {
    let mut word = [0u8; 8];
    let n = bytes.len().min(8);
    word[..n].copy_from_slice(&bytes[..n]);
    u64::from_le_bytes(word)
}

/// The mix of a first-half key word (blocks and tail alike).
fn murmur_k1(k1: u64) -> u64 {
    k1.wrapping_mul(MURMUR_C1)
        .rotate_left(31)
        .wrapping_mul(MURMUR_C2)
}

/// The mix of a second-half key word.
fn murmur_k2(k2: u64) -> u64 {
    k2.wrapping_mul(MURMUR_C2)
        .rotate_left(33)
        .wrapping_mul(MURMUR_C1)
}

/// MurmurHash3_x64_128 of `data` with `seed` (Alembic uses seed 0); the two
/// 64-bit halves in the order the reference stores them.
pub fn murmur3_x64_128(data: &[u8], seed: u32) -> [u64; 2] {
    let mut h1 = u64::from(seed);
    let mut h2 = u64::from(seed);
    let mut blocks = data.chunks_exact(16);
    for block in &mut blocks {
        h1 ^= murmur_k1(u64_le(&block[..8]));
        h1 = h1
            .rotate_left(27)
            .wrapping_add(h2)
            .wrapping_mul(5)
            .wrapping_add(0x52dc_e729);
        h2 ^= murmur_k2(u64_le(&block[8..]));
        h2 = h2
            .rotate_left(31)
            .wrapping_add(h1)
            .wrapping_mul(5)
            .wrapping_add(0x3849_5ab5);
    }
    let tail = blocks.remainder();
    if tail.len() > 8 {
        h2 ^= murmur_k2(u64_le(&tail[8..]));
    }
    if !tail.is_empty() {
        h1 ^= murmur_k1(u64_le(&tail[..tail.len().min(8)]));
    }
    let len = data.len() as u64;
    h1 ^= len;
    h2 ^= len;
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    h1 = fmix64(h1);
    h2 = fmix64(h2);
    h1 = h1.wrapping_add(h2);
    h2 = h2.wrapping_add(h1);
    [h1, h2]
}

/// The 16 bytes of a digest as Alembic stores them.
pub fn digest_bytes(words: [u64; 2]) -> [u8; 16] {
    let mut out = [0u8; 16];
    out[..8].copy_from_slice(&words[0].to_le_bytes());
    out[8..].copy_from_slice(&words[1].to_le_bytes());
    out
}

const SPOOKY_VARS: usize = 12;
const SPOOKY_BLOCK: usize = SPOOKY_VARS * 8;
const SPOOKY_BUFFER: usize = 2 * SPOOKY_BLOCK;
const SPOOKY_CONST: u64 = 0xdead_beef_dead_beef;

/// SpookyHash V2, incremental (Init/Update/Final of the reference).
#[derive(Clone)]
pub struct SpookyHash {
    buffer: [u8; SPOOKY_BUFFER],
    state: [u64; SPOOKY_VARS],
    length: usize,
    remainder: usize,
}

fn words<const N: usize>(bytes: &[u8]) -> [u64; N] {
    let mut out = [0u64; N];
    for (word, chunk) in out.iter_mut().zip(bytes.chunks(8)) {
        *word = u64_le(chunk);
    }
    out
}

fn spooky_mix(data: &[u64; SPOOKY_VARS], s: &mut [u64; SPOOKY_VARS]) {
    const ROT: [u32; SPOOKY_VARS] = [11, 32, 43, 31, 17, 28, 39, 57, 55, 54, 22, 46];
    for i in 0..SPOOKY_VARS {
        s[i] = s[i].wrapping_add(data[i]);
        s[(i + 2) % SPOOKY_VARS] ^= s[(i + 10) % SPOOKY_VARS];
        s[(i + 11) % SPOOKY_VARS] ^= s[i];
        s[i] = s[i].rotate_left(ROT[i]);
        s[(i + 11) % SPOOKY_VARS] =
            s[(i + 11) % SPOOKY_VARS].wrapping_add(s[(i + 1) % SPOOKY_VARS]);
    }
}

fn spooky_end_partial(h: &mut [u64; SPOOKY_VARS]) {
    const ROT: [u32; SPOOKY_VARS] = [44, 15, 34, 21, 38, 33, 10, 13, 38, 53, 42, 54];
    for (i, &rotation) in ROT.iter().enumerate() {
        // Step i: h[i+11] += h[i+1]; h[i+2] ^= h[i+11]; h[i+1] = rot(h[i+1]).
        let a = (i + 11) % SPOOKY_VARS;
        let b = (i + 1) % SPOOKY_VARS;
        let c = (i + 2) % SPOOKY_VARS;
        h[a] = h[a].wrapping_add(h[b]);
        h[c] ^= h[a];
        h[b] = h[b].rotate_left(rotation);
    }
}

fn spooky_end(data: &[u64; SPOOKY_VARS], h: &mut [u64; SPOOKY_VARS]) {
    for (state, word) in h.iter_mut().zip(data) {
        *state = state.wrapping_add(*word);
    }
    spooky_end_partial(h);
    spooky_end_partial(h);
    spooky_end_partial(h);
}

fn spooky_short_mix(h: &mut [u64; 4]) {
    const ROT: [u32; 12] = [50, 52, 30, 41, 54, 48, 38, 37, 62, 34, 5, 36];
    for (step, &r) in ROT.iter().enumerate() {
        let x = (step + 2) % 4;
        let y = (step + 3) % 4;
        let z = step % 4;
        h[x] = h[x].rotate_left(r);
        h[x] = h[x].wrapping_add(h[y]);
        h[z] ^= h[x];
    }
}

/// The final mix of the short hash; Alembic also uses it to fold a sample
/// digest into a property's running hash.
pub fn spooky_short_end(h: &mut [u64; 4]) {
    const ROT: [u32; 11] = [15, 52, 26, 51, 28, 9, 47, 54, 32, 25, 63];
    for (step, &r) in ROT.iter().enumerate() {
        // Step k: h[k+3] ^= h[k+2]; h[k+2] = rot(h[k+2]); h[k+3] += h[k+2].
        let x = (step + 3) % 4;
        let y = (step + 2) % 4;
        h[x] ^= h[y];
        h[y] = h[y].rotate_left(r);
        h[x] = h[x].wrapping_add(h[y]);
    }
}

fn spooky_short(message: &[u8], seed1: u64, seed2: u64) -> (u64, u64) {
    let length = message.len();
    let mut h = [seed1, seed2, SPOOKY_CONST, SPOOKY_CONST];
    let mut rest = message;
    if length > 15 {
        while rest.len() >= 32 {
            let w: [u64; 4] = words(&rest[..32]);
            h[2] = h[2].wrapping_add(w[0]);
            h[3] = h[3].wrapping_add(w[1]);
            spooky_short_mix(&mut h);
            h[0] = h[0].wrapping_add(w[2]);
            h[1] = h[1].wrapping_add(w[3]);
            rest = &rest[32..];
        }
        if rest.len() >= 16 {
            let w: [u64; 2] = words(&rest[..16]);
            h[2] = h[2].wrapping_add(w[0]);
            h[3] = h[3].wrapping_add(w[1]);
            spooky_short_mix(&mut h);
            rest = &rest[16..];
        }
    }
    h[3] = h[3].wrapping_add((length as u64) << 56);
    if rest.is_empty() {
        h[2] = h[2].wrapping_add(SPOOKY_CONST);
        h[3] = h[3].wrapping_add(SPOOKY_CONST);
    } else {
        // The remaining 1..15 bytes: the first 8 go to c, the others to d,
        // each as a little-endian number.
        let first = &rest[..rest.len().min(8)];
        h[2] = h[2].wrapping_add(u64_le(first));
        if rest.len() > 8 {
            h[3] = h[3].wrapping_add(u64_le(&rest[8..]));
        }
    }
    let mut all = h;
    spooky_short_end(&mut all);
    (all[0], all[1])
}

impl SpookyHash {
    /// `Init(seed1, seed2)`.
    pub fn new(seed1: u64, seed2: u64) -> SpookyHash {
        let mut state = [0u64; SPOOKY_VARS];
        state[0] = seed1;
        state[1] = seed2;
        SpookyHash {
            buffer: [0; SPOOKY_BUFFER],
            state,
            length: 0,
            remainder: 0,
        }
    }

    pub fn update(&mut self, message: &[u8]) {
        let new_length = message.len() + self.remainder;
        if new_length < SPOOKY_BUFFER {
            self.buffer[self.remainder..new_length].copy_from_slice(message);
            self.length += message.len();
            self.remainder = new_length;
            return;
        }
        let mut h = if self.length < SPOOKY_BUFFER {
            // The two seeds and the constant, repeated over the 12 words.
            let seeds = [self.state[0], self.state[1], SPOOKY_CONST];
            std::array::from_fn(|i| seeds[i % 3])
        } else {
            self.state
        };
        self.length += message.len();
        let mut rest = message;
        if self.remainder > 0 {
            let prefix = SPOOKY_BUFFER - self.remainder;
            self.buffer[self.remainder..].copy_from_slice(&rest[..prefix]);
            let first: [u64; SPOOKY_VARS] = words(&self.buffer[..SPOOKY_BLOCK]);
            let second: [u64; SPOOKY_VARS] = words(&self.buffer[SPOOKY_BLOCK..]);
            spooky_mix(&first, &mut h);
            spooky_mix(&second, &mut h);
            rest = &rest[prefix..];
        }
        while rest.len() >= SPOOKY_BLOCK {
            let block: [u64; SPOOKY_VARS] = words(&rest[..SPOOKY_BLOCK]);
            spooky_mix(&block, &mut h);
            rest = &rest[SPOOKY_BLOCK..];
        }
        self.remainder = rest.len();
        self.buffer[..rest.len()].copy_from_slice(rest);
        self.state = h;
    }

    /// `Final`: the two 64-bit halves; the hash can go on being updated.
    pub fn finish(&self) -> (u64, u64) {
        if self.length < SPOOKY_BUFFER {
            return spooky_short(&self.buffer[..self.length], self.state[0], self.state[1]);
        }
        let mut h = self.state;
        let mut remainder = self.remainder;
        let mut buffer = self.buffer;
        let mut start = 0;
        if remainder >= SPOOKY_BLOCK {
            let block: [u64; SPOOKY_VARS] = words(&buffer[..SPOOKY_BLOCK]);
            spooky_mix(&block, &mut h);
            start = SPOOKY_BLOCK;
            remainder -= SPOOKY_BLOCK;
        }
        let last = &mut buffer[start..start + SPOOKY_BLOCK];
        last[remainder..].fill(0);
        last[SPOOKY_BLOCK - 1] = remainder as u8;
        let block: [u64; SPOOKY_VARS] = words(last);
        spooky_end(&block, &mut h);
        (h[0], h[1])
    }

    /// `Hash128` of a whole message with two seeds.
    pub fn hash128(message: &[u8], seed1: u64, seed2: u64) -> (u64, u64) {
        let mut hash = SpookyHash::new(seed1, seed2);
        hash.update(message);
        hash.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// SMHasher's verification value for MurmurHash3_x64_128: hash the keys
    /// {0}, {0,1}, ... {0..254} with seed 256 - len, then hash the
    /// concatenated digests with seed 0; the first 4 bytes, little-endian.
    #[test]
    fn murmur3_smhasher_verification_value() {
        let key: Vec<u8> = (0..=255u8).collect();
        let mut all = Vec::new();
        for len in 0..256usize {
            let digest = murmur3_x64_128(&key[..len], (256 - len) as u32);
            all.extend_from_slice(&digest_bytes(digest));
        }
        let final_digest = digest_bytes(murmur3_x64_128(&all, 0));
        let verification = u32::from_le_bytes([
            final_digest[0],
            final_digest[1],
            final_digest[2],
            final_digest[3],
        ]);
        assert_eq!(verification, 0x6384_BA69);
    }

    #[test]
    fn murmur3_known_vectors() {
        assert_eq!(murmur3_x64_128(b"", 0), [0, 0]);
        assert_eq!(
            hex(&digest_bytes(murmur3_x64_128(
                b"The quick brown fox jumps over the lazy dog",
                0
            ))),
            "6c1b07bc7bbc4be347939ac4a93c437a"
        );
    }

    /// Digests stored by the Alembic library itself in
    /// `tests/data/hairutil_Bangs_100.abc` (the 16 bytes before each sample).
    #[test]
    fn murmur3_matches_alembic_sample_digests() {
        let file = crate::abc::test_support::test_data("hairutil_Bangs_100.abc");
        // The P sample: a data block at offset 0x28 (size, digest, floats).
        let size = u64::from_le_bytes(file[0x28..0x30].try_into().unwrap()) as usize;
        let block = &file[0x30..0x30 + size];
        let (digest, data) = block.split_at(16);
        assert_eq!(data.len(), 1165 * 12);
        assert_eq!(digest_bytes(murmur3_x64_128(data, 0)), digest);
    }

    /// SpookyHash V2 test vectors: Hash32 (the low 32 bits of Hash128 with
    /// both seeds 0) of buf[i] = i + 128 for the first lengths, from the
    /// reference implementation's test program (testspooky.cpp).
    #[test]
    fn spooky_reference_vectors() {
        const EXPECTED: [u32; 8] = [
            0x6bf50919, 0x70de1d26, 0xa2b37298, 0x35bc5fbf, 0x8223b279, 0x5bcb315e, 0x53fe88a1,
            0xf9f1a233,
        ];
        let buffer: Vec<u8> = (0..512).map(|i| (i + 128) as u8).collect();
        for (len, expected) in EXPECTED.iter().enumerate() {
            let (h1, _) = SpookyHash::hash128(&buffer[..len], 0, 0);
            assert_eq!(h1 as u32, *expected, "length {len}");
        }
    }

    /// Incremental updates in any split give the one-shot hash, short and
    /// long messages alike.
    #[test]
    fn spooky_incremental_matches_one_shot() {
        let message: Vec<u8> = (0..1000u32).map(|i| (i * 7 + 3) as u8).collect();
        for len in [0, 1, 15, 16, 31, 95, 96, 191, 192, 193, 500, 1000] {
            let whole = SpookyHash::hash128(&message[..len], 1, 2);
            for split in [0, 1, 7, 96, 150] {
                let split = split.min(len);
                let mut hash = SpookyHash::new(1, 2);
                hash.update(&message[..split]);
                hash.update(&message[split..len]);
                assert_eq!(hash.finish(), whole, "len {len} split {split}");
            }
        }
    }
}
