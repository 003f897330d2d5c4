//! The bearer token of mutating routes: where it comes from (`[http] auth_token`, `[http] auth_token_file` or
//! the environment variable [`TOKEN_ENV`]; at most one of them), how it is kept (a [`Secret`] that never
//! prints) and how a presented token is compared with it (in constant time, [`subtle`]).

use std::path::Path;

use serde::{Deserialize, Deserializer};
use subtle::{Choice, ConstantTimeEq};

use crate::error::{DaemonError, Result};

/// The environment variable that may hold the bearer token (instead of the config file).
pub const TOKEN_ENV: &str = "SHIFT_AUTH_TOKEN";

/// A secret string: compared, never shown. `Debug` prints `<redacted>` (or `<none>` when empty), so a config
/// or state printed to a log never carries it.
#[derive(Clone, Default, PartialEq, Eq)]
pub struct Secret(String);

impl Secret {
    /// Wraps a value.
    pub fn new(value: impl Into<String>) -> Self {
        Self(value.into())
    }

    /// True when no secret is set.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The value, for the one comparison that needs it.
    fn bytes(&self) -> &[u8] {
        self.0.as_bytes()
    }
}

impl std::fmt::Debug for Secret {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_empty() { "<none>" } else { "<redacted>" })
    }
}

impl From<&str> for Secret {
    fn from(v: &str) -> Self {
        Self::new(v)
    }
}

impl<'de> Deserialize<'de> for Secret {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        String::deserialize(d).map(Self)
    }
}

/// Whether `given` equals the token, in time that depends only on the token's length (never on where the
/// first difference is, nor on `given`'s length): every byte of the token is compared, with `subtle`'s
/// constant-time operations, and the lengths are compared the same way.
pub fn token_matches(given: &[u8], token: &Secret) -> Choice {
    let expected = token.bytes();
    let same_len = (given.len() as u64).ct_eq(&(expected.len() as u64));
    let mut same = Choice::from(1);
    for (i, e) in expected.iter().enumerate() {
        // Past the end of `given`, compare with 0: a mismatch already, through `same_len`.
        let g = given.get(i).copied().unwrap_or(0);
        same &= g.ct_eq(e);
    }
    same & same_len
}

/// Where the token in force came from (logged at start-up instead of the token).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TokenSource {
    /// No token: every route is open.
    None,
    /// `[http] auth_token`.
    Config,
    /// `[http] auth_token_file`.
    File,
    /// The environment variable [`TOKEN_ENV`].
    Env,
}

/// The token from the three places it may be given; more than one set is a configuration error (a token
/// silently ignored is worse than a refusal to start). `env` looks up an environment variable (the process
/// environment in `shiftd serve`; tests pass their own). A token file holds the token and optionally a final
/// newline; an empty file, or a token with whitespace or control characters inside, is an error.
pub fn resolve(
    config_token: &Secret,
    token_file: &Path,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(Secret, TokenSource)> {
    let from_env = env(TOKEN_ENV).filter(|v| !v.is_empty());
    let from_file = !token_file.as_os_str().is_empty();
    let mut set = Vec::new();
    if !config_token.is_empty() {
        set.push("[http] auth_token");
    }
    if from_file {
        set.push("[http] auth_token_file");
    }
    if from_env.is_some() {
        set.push(TOKEN_ENV);
    }
    if set.len() > 1 {
        return Err(DaemonError::config(format!(
            "the bearer token is given more than once ({}); keep one",
            set.join(", ")
        )));
    }
    let (token, source) = if let Some(v) = from_env {
        (v, TokenSource::Env)
    } else if from_file {
        let text = std::fs::read_to_string(token_file)
            .map_err(|e| DaemonError::config(format!("[http] auth_token_file {}: {e}", token_file.display())))?;
        let token = text.strip_suffix('\n').unwrap_or(&text);
        let token = token.strip_suffix('\r').unwrap_or(token).to_owned();
        if token.is_empty() {
            return Err(DaemonError::config(format!(
                "[http] auth_token_file {} is empty",
                token_file.display()
            )));
        }
        (token, TokenSource::File)
    } else if !config_token.is_empty() {
        (config_token.0.clone(), TokenSource::Config)
    } else {
        return Ok((Secret::default(), TokenSource::None));
    };
    if token.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(DaemonError::config(format!(
            "the bearer token from {} holds whitespace or control characters",
            set.first().copied().unwrap_or("the configuration")
        )));
    }
    Ok((Secret(token), source))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_env(_: &str) -> Option<String> {
        None
    }

    #[test]
    fn the_comparison_is_subtles_constant_time_one() {
        // The type says it: only subtle's constant-time operations make a `Choice`, and `token_matches`
        // answers one (a plain `==` or an early-exit loop would give a `bool`).
        let token = Secret::new("s3cret");
        let answer: Choice = token_matches(b"s3cret", &token);
        assert!(bool::from(answer));
        for wrong in [&b"s3creT"[..], b"s3cre", b"s3cret!", b"", b"x"] {
            assert!(!bool::from(token_matches(wrong, &token)), "{wrong:?}");
        }
    }

    #[test]
    fn secrets_never_print() {
        let s = Secret::new("hunter2");
        assert_eq!(format!("{s:?}"), "<redacted>");
        assert_eq!(format!("{:?}", Secret::default()), "<none>");
    }

    #[test]
    fn the_token_comes_from_one_place() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = dir.path().join("token");
        std::fs::write(&file, "from-file\n").expect("write");
        let none = Path::new("");
        let env = |k: &str| (k == TOKEN_ENV).then(|| "from-env".to_owned());

        assert_eq!(
            resolve(&Secret::default(), none, &no_env).expect("none"),
            (Secret::default(), TokenSource::None)
        );
        assert_eq!(
            resolve(&"cfg".into(), none, &no_env).expect("config"),
            (Secret::new("cfg"), TokenSource::Config)
        );
        assert_eq!(
            resolve(&Secret::default(), &file, &no_env).expect("file"),
            (Secret::new("from-file"), TokenSource::File)
        );
        assert_eq!(
            resolve(&Secret::default(), none, &env).expect("env"),
            (Secret::new("from-env"), TokenSource::Env)
        );
        // An empty variable is no token.
        let empty = |_: &str| Some(String::new());
        assert_eq!(
            resolve(&Secret::default(), none, &empty).expect("empty env").1,
            TokenSource::None
        );

        let e = resolve(&"cfg".into(), &file, &env).expect_err("three sources");
        assert!(e.to_string().contains("more than once"), "{e}");
        assert!(
            !e.to_string().contains("from-env") && !e.to_string().contains("cfg\""),
            "{e}"
        );
        std::fs::write(&file, "\n").expect("write");
        assert!(resolve(&Secret::default(), &file, &no_env).is_err(), "empty file");
        std::fs::write(&file, "two words").expect("write");
        let e = resolve(&Secret::default(), &file, &no_env).expect_err("whitespace");
        assert!(!e.to_string().contains("two words"), "the token is never echoed: {e}");
        assert!(resolve(&Secret::default(), &dir.path().join("missing"), &no_env).is_err());
    }
}
