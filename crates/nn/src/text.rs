//! Text that this crate and `neurarm-physics` share: a text file read with a bound on its size,
//! so that a path to something that is not the small file it should be (`/dev/zero`, a log
//! given where a configuration belongs) gives an error at once instead of filling the memory;
//! and numbers written for messages.

use std::io::Read;
use std::path::Path;

/// The UTF-8 text of `path`, if it holds at most `max_bytes`. Reads at most `max_bytes + 1`
/// bytes whatever the file is (a pipe, a device), so it always ends.
pub fn read_text(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    file.take(max_bytes.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("larger than {} MiB, the most this file may hold: is it the right file?", max_bytes >> 20),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text (at byte {})", e.utf8_error().valid_up_to()))
    })
}

/// `value` for a message: as written for ordinary magnitudes, in exponent form beyond them
/// (1.7e308 rather than 309 digits).
pub fn show_number(value: f64) -> String {
    if value == 0.0 || !value.is_finite() || (1e-4..1e15).contains(&value.abs()) {
        value.to_string()
    } else {
        format!("{value:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_device_is_refused_after_the_bound() {
        let e = read_text(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("larger than 1 MiB"), "{e}");
    }

    #[test]
    fn text_up_to_the_bound_is_read_and_bytes_that_are_no_text_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.toml");
        std::fs::write(&path, "x = 1\n").unwrap();
        assert_eq!(read_text(&path, 6).unwrap(), "x = 1\n");
        assert!(read_text(&path, 5).is_err());
        std::fs::write(&path, b"x = \xff").unwrap();
        assert!(read_text(&path, 100).unwrap_err().to_string().contains("not UTF-8 text (at byte 4)"));
    }
}
