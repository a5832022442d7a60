//! The loader never panics: random bytes and random mutations of the bundled scenes and scripts
//! (byte flips, deletions, duplications, number replacements) either load or give an error.

use dissect::scene::{Scene, Script};
use proptest::prelude::*;

const SCENES: [&str; 4] = [
    include_str!("../scenes/meninges.ron"),
    include_str!("../scenes/cylinder.ron"),
    include_str!("../scenes/sphere.ron"),
    include_str!("../scenes/volume.ron"),
];
const SCRIPTS: [&str; 4] = [
    include_str!("../scenes/scripts/meninges.ron"),
    include_str!("../scenes/scripts/cylinder.ron"),
    include_str!("../scenes/scripts/sphere.ron"),
    include_str!("../scenes/scripts/volume.ron"),
];

/// Numbers that probe the range checks.
const NUMBERS: [&str; 14] = [
    "0",
    "-1",
    "1e30",
    "-1e-30",
    "NaN",
    "inf",
    "-inf",
    "4294967296",
    "0.5",
    "1",
    "100000",
    "-0.0",
    "1.0e",
    "18446744073709551616",
];

#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, byte: u8 },
    Delete { at: usize, len: usize },
    Duplicate { at: usize, len: usize, to: usize },
    Number { nth: usize, with: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), 1usize..80, any::<usize>()).prop_map(|(at, len, to)| Mutation::Duplicate {
            at,
            len,
            to
        }),
        (any::<usize>(), 0..NUMBERS.len()).prop_map(|(nth, with)| Mutation::Number { nth, with }),
    ]
}

fn apply(src: &[u8], m: &Mutation) -> Vec<u8> {
    let mut out = src.to_vec();
    let n = out.len().max(1);
    match *m {
        Mutation::Flip { at, byte } => {
            if !out.is_empty() {
                out[at % n] = byte;
            }
        }
        Mutation::Delete { at, len } => {
            let a = at % n;
            let b = (a + len).min(out.len());
            out.drain(a..b);
        }
        Mutation::Duplicate { at, len, to } => {
            let a = at % n;
            let b = (a + len).min(out.len());
            let piece = out[a..b].to_vec();
            let t = to % (out.len() + 1);
            out.splice(t..t, piece);
        }
        Mutation::Number { nth, with } => {
            // Replace the nth run of digits (with its sign, point and exponent).
            let text = String::from_utf8_lossy(&out).into_owned();
            let runs: Vec<(usize, usize)> = number_runs(&text);
            if !runs.is_empty() {
                let (a, b) = runs[nth % runs.len()];
                let mut s = text;
                s.replace_range(a..b, NUMBERS[with]);
                out = s.into_bytes();
            }
        }
    }
    out
}

fn number_runs(s: &str) -> Vec<(usize, usize)> {
    let bytes = s.as_bytes();
    let mut runs = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = if i > 0 && bytes[i - 1] == b'-' { i - 1 } else { i };
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.' || bytes[i] == b'e') {
                i += 1;
            }
            runs.push((start, i));
        } else {
            i += 1;
        }
    }
    runs
}

/// Loads as a scene and as a script; only a panic fails.
fn feed(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    if let Err(e) = Scene::from_str(&text, "fuzz.ron") {
        let msg = e.to_string();
        assert!(msg.starts_with("fuzz.ron:"), "{msg}");
    }
    if let Err(e) = Script::from_str(&text, "fuzz.ron") {
        let msg = e.to_string();
        assert!(msg.starts_with("fuzz.ron:"), "{msg}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        feed(&bytes);
    }

    #[test]
    fn mutated_scenes_never_panic(which in 0..SCENES.len(), ms in proptest::collection::vec(mutation(), 1..6)) {
        let mut src = SCENES[which].as_bytes().to_vec();
        for m in &ms {
            src = apply(&src, m);
        }
        feed(&src);
    }

    #[test]
    fn mutated_scripts_never_panic(which in 0..SCRIPTS.len(), ms in proptest::collection::vec(mutation(), 1..6)) {
        let mut src = SCRIPTS[which].as_bytes().to_vec();
        for m in &ms {
            src = apply(&src, m);
        }
        feed(&src);
    }

    #[test]
    fn single_number_replacements_never_panic(which in 0..SCENES.len(), nth in any::<usize>(), with in 0..NUMBERS.len()) {
        let src = apply(SCENES[which].as_bytes(), &Mutation::Number { nth, with });
        feed(&src);
    }
}

/// Deep nesting must be refused, not overflow the stack (RON has a recursion limit; so has the
/// position finder).
#[test]
fn deep_nesting_is_an_error() {
    let deep = format!("{}{}", "(".repeat(100_000), ")".repeat(100_000));
    feed(deep.as_bytes());
    let deep = format!("Scene(title: \"x\", tissue: {}", "[".repeat(100_000));
    feed(deep.as_bytes());
}
