//! The `fmuResourceLocation` URI a host passes to `fmi2Instantiate`, turned into a folder path
//! of the platform the binary runs on. FMI 2.0 asks for a `file` URI (RFC 8089); hosts pass it
//! in several forms, which must all resolve:
//!
//! - `file:///home/u/x/resources`, `file:/home/u/x/resources`, `file://localhost/home/…`;
//! - on Windows a drive letter, `file:///C:/x/resources` (fmpy, Simulink), `file:/C:/x` (some
//!   Dymola versions), the old `file:///C|/x`, a percent-encoded `C%3A`, backslashes in place
//!   of slashes (`file:///C:\x\resources`, sent by some Windows tools);
//! - on Windows a share, `file://server/share/x` or `file:////server/share/x`, which is the UNC
//!   path `\\server\share\x`.
//!
//! Percent-encoding is decoded. A host name other than `localhost` is an error on Unix, where
//! there is no UNC path to map it to. The conversion is a pure function of the URI and a
//! [`PathStyle`], so every platform's rules are tested on any machine.

use percent_encoding::percent_decode_str;

/// Which platform's paths a resource URI is turned into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathStyle {
    /// `/`-rooted paths; a URI naming a remote host is refused.
    Unix,
    /// Drive-letter paths (`C:\x`) and UNC shares (`\\server\share\x`), with backslashes.
    Windows,
}

impl PathStyle {
    /// The style of the platform this code is compiled for.
    pub const fn native() -> Self {
        if cfg!(windows) {
            PathStyle::Windows
        } else {
            PathStyle::Unix
        }
    }
}

/// Why a resource location URI names no folder in a [`PathStyle`]; each error holds the URI.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ResourceUriError {
    /// Another scheme than `file:`, or none.
    #[error("resource location '{0}' is not a file URI (file:///…)")]
    NotFileUri(String),
    /// Percent-decoding gives bytes that are not UTF-8.
    #[error("resource location '{0}' is not valid UTF-8 after percent-decoding")]
    NotUtf8(String),
    /// Percent-decoding gives a NUL, which no path holds.
    #[error("resource location '{0}' holds a NUL character")]
    Nul(String),
    /// A host other than `localhost`, on Unix (no UNC path to map it to).
    #[error("resource location '{uri}' names the remote host '{host}'")]
    RemoteHost {
        /// The URI.
        uri: String,
        /// The host it names.
        host: String,
    },
    /// `file:////` with no server name before the share.
    #[error("resource location '{0}' names a share without a server")]
    ShareWithoutServer(String),
    /// A relative path.
    #[error("resource location '{0}' is not an absolute path")]
    NotAbsolute(String),
}

/// The folder a resource location URI names, as a path in `style` (the folder may not exist).
/// Errors say what is wrong with the URI.
pub fn resource_path(uri: &str, style: PathStyle) -> Result<String, ResourceUriError> {
    let rest = match uri.get(..5) {
        Some(scheme) if scheme.eq_ignore_ascii_case("file:") => &uri[5..],
        _ => return Err(ResourceUriError::NotFileUri(uri.to_owned())),
    };
    // Windows tools may write the URI with backslashes; a backslash is never part of a
    // Windows file name, so it can only be a separator there.
    let rest = match style {
        PathStyle::Windows => rest.replace('\\', "/"),
        PathStyle::Unix => rest.to_owned(),
    };
    let (host, path) = match rest.strip_prefix("//") {
        Some(after) => match after.find('/') {
            Some(slash) => (&after[..slash], &after[slash..]),
            None => (after, ""),
        },
        None => ("", rest.as_str()),
    };
    let decoded = percent_decode_str(path).decode_utf8().map_err(|_| ResourceUriError::NotUtf8(uri.to_owned()))?;
    if decoded.contains('\0') {
        return Err(ResourceUriError::Nul(uri.to_owned()));
    }
    let host = if host.eq_ignore_ascii_case("localhost") { "" } else { host };
    match style {
        PathStyle::Unix => {
            if !host.is_empty() {
                return Err(ResourceUriError::RemoteHost { uri: uri.to_owned(), host: host.to_owned() });
            }
            if !decoded.starts_with('/') {
                return Err(ResourceUriError::NotAbsolute(uri.to_owned()));
            }
            Ok(decoded.into_owned())
        }
        PathStyle::Windows => {
            let decoded = decoded.replace('\\', "/");
            if !host.is_empty() {
                return Ok(unc_path(host, &decoded));
            }
            // `file:////server/share/x`: the share written as a path.
            if let Some(share) = decoded.strip_prefix("//") {
                let (server, tail) = share.split_at(share.find('/').unwrap_or(share.len()));
                if server.is_empty() {
                    return Err(ResourceUriError::ShareWithoutServer(uri.to_owned()));
                }
                return Ok(unc_path(server, tail));
            }
            let local = decoded.strip_prefix('/').unwrap_or(&decoded);
            match drive_letter(local) {
                Some((drive, tail)) => Ok(format!("{drive}:{}", backslashes(if tail.is_empty() { "/" } else { tail }))),
                None if decoded.starts_with('/') => Ok(backslashes(&decoded)),
                None => Err(ResourceUriError::NotAbsolute(uri.to_owned())),
            }
        }
    }
}

/// `C:/x` or `C|/x` → (`C`, `/x`); the letter must be followed by a separator or the end.
fn drive_letter(path: &str) -> Option<(char, &str)> {
    let mut chars = path.chars();
    let letter = chars.next().filter(char::is_ascii_alphabetic)?;
    if !matches!(chars.next(), Some(':' | '|')) {
        return None;
    }
    let tail = &path[2..];
    (tail.is_empty() || tail.starts_with('/')).then_some((letter, tail))
}

fn unc_path(server: &str, tail: &str) -> String {
    format!("\\\\{server}{}", backslashes(tail))
}

fn backslashes(path: &str) -> String {
    path.replace('/', "\\")
}
