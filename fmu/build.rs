//! Hashes the sources this binary is built from (its own, the models', the physics', the nets',
//! the export layer's and Cargo.lock) into `NEURARM_FMU_SOURCES`, which the library carries as a marker:
//! neurarm packs a cross build for another platform only if it carries the same hash as the
//! linux64 library, so an FMU never ships binaries of different sources (a file's age cannot
//! tell: cargo relinks a library whenever the features it is built with change).

use std::path::{Path, PathBuf};

const SOURCES: [&str; 11] = [
    "fmu/src",
    "crates/models/src",
    "crates/models/Cargo.toml",
    "crates/physics/src",
    "crates/physics/Cargo.toml",
    "crates/nn/src",
    "crates/nn/Cargo.toml",
    "crates/fmi-export/src",
    "crates/fmi-export/Cargo.toml",
    "fmu/Cargo.toml",
    "Cargo.lock",
];

/// Every file under `path` (or `path` itself), in a fixed order.
fn files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(path).expect("readable source folder").map(|e| e.unwrap().path()).collect();
        entries.sort();
        for e in entries {
            files(&e, out);
        }
    } else if path.is_file() {
        out.push(path.to_path_buf());
    }
}

fn main() {
    let root = Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("..");
    // FNV-1a, 64 bits: a fingerprint to tell builds apart, not a defence against tampering.
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for b in bytes {
            hash ^= u64::from(*b);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for source in SOURCES {
        let path = root.join(source);
        println!("cargo:rerun-if-changed={}", path.display());
        let mut found = Vec::new();
        files(&path, &mut found);
        for file in found {
            let name = file.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
            let bytes = std::fs::read(&file).unwrap();
            feed(name.as_bytes());
            feed(&(bytes.len() as u64).to_le_bytes());
            feed(&bytes);
        }
    }
    println!("cargo:rustc-env=NEURARM_FMU_SOURCES={hash:016x}");
}
