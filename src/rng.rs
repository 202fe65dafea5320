//! Random streams. Every random draw of a run comes from a generator seeded by the
//! spec seed and the name of the task that draws it (a grid combination, a Monte Carlo
//! run on one trajectory), so the draws do not depend on how tasks are spread over
//! threads, nor on which other tasks run.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sha2::{Digest, Sha256};

/// A generator for the task named by `parts` under the run `seed`.
///
/// The 256-bit ChaCha seed is the SHA-256 of the seed and the parts, so distinct tasks
/// get independent streams, and ("a", "bc") differs from ("ab", "c").
pub fn task_rng(seed: u64, parts: &[&dyn std::fmt::Display]) -> ChaCha8Rng {
    let mut hasher = Sha256::new();
    hasher.update(seed.to_le_bytes());
    for part in parts {
        let text = part.to_string();
        hasher.update((text.len() as u64).to_le_bytes());
        hasher.update(text.as_bytes());
    }
    ChaCha8Rng::from_seed(hasher.finalize().into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    #[test]
    fn streams_depend_on_seed_and_every_part() {
        let draw = |seed, parts: &[&dyn std::fmt::Display]| task_rng(seed, parts).random::<u64>();
        assert_eq!(draw(1, &[&"mc", &3]), draw(1, &[&"mc", &3]));
        assert_ne!(draw(1, &[&"mc", &3]), draw(2, &[&"mc", &3]));
        assert_ne!(draw(1, &[&"mc", &3]), draw(1, &[&"mc", &4]));
        assert_ne!(draw(1, &[&"a", &"bc"]), draw(1, &[&"ab", &"c"]));
    }
}
