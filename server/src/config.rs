//! How the server runs: where it listens, the token, and the limits that keep it
//! bounded (body size, sessions, queue, history, timeouts).

use std::net::SocketAddr;
use std::time::Duration;

use crate::error::ServeError;

/// The default address: loopback only.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";

/// The largest request body by default (formats.md: 1 MiB).
pub const DEFAULT_BODY_LIMIT: usize = 1 << 20;

/// Settings of `ivlmap serve`.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeConfig {
    /// `host:port` to listen on; port 0 picks a free port.
    pub addr: String,
    /// When set, every `/api` request needs `Authorization: Bearer <token>`. Required
    /// when `addr` is not a loopback address.
    pub token: Option<String>,
    /// Request bodies over this many bytes are refused with 413.
    pub body_limit: usize,
    /// Sessions idle this long are dropped.
    pub session_ttl: Duration,
    /// At most this many sessions at once (a new one beyond gets 503).
    pub max_sessions: usize,
    /// At most this many instructions waiting for the model (one beyond gets 503).
    pub max_queue: usize,
    /// Instructions the model answers at once (1 for a local model).
    pub workers: usize,
    /// Instructions a session can undo.
    pub undo_depth: usize,
    /// Executed instructions a session holds before it asks to be reset.
    pub max_turns: usize,
    /// Longest an instruction may take, queue wait included (then 503).
    pub request_timeout: Duration,
    /// Longest instruction text, in characters.
    pub max_instruction_chars: usize,
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            addr: DEFAULT_ADDR.to_string(),
            token: None,
            body_limit: DEFAULT_BODY_LIMIT,
            session_ttl: Duration::from_secs(30 * 60),
            max_sessions: 256,
            max_queue: 512,
            workers: 1,
            undo_depth: 32,
            max_turns: 1000,
            request_timeout: Duration::from_secs(300),
            max_instruction_chars: 2000,
        }
    }
}

impl ServeConfig {
    /// Checks the settings against the address they will listen on: a token is required
    /// off loopback, and must not be blank; limits must be positive.
    ///
    /// # Errors
    /// [`ServeError::TokenRequired`], [`ServeError::Config`].
    pub fn check(&self, addr: SocketAddr) -> Result<(), ServeError> {
        if let Some(t) = &self.token {
            if t.trim().is_empty() {
                return Err(ServeError::Config {
                    message:
                        "--token is empty: give a secret string (or leave --token out on loopback)"
                            .into(),
                });
            }
        } else if !addr.ip().is_loopback() {
            return Err(ServeError::TokenRequired { addr });
        }
        for (what, v) in [
            ("the body limit", self.body_limit),
            ("the session limit", self.max_sessions),
            ("the queue limit", self.max_queue),
            ("the number of workers", self.workers),
            ("the turn limit", self.max_turns),
            ("the instruction length limit", self.max_instruction_chars),
        ] {
            if v == 0 {
                return Err(ServeError::Config {
                    message: format!("{what} must be at least 1"),
                });
            }
        }
        if self.session_ttl.is_zero() || self.request_timeout.is_zero() {
            return Err(ServeError::Config {
                message: "the session lifetime and the request timeout must be positive".into(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_is_required_off_loopback() {
        let c = ServeConfig::default();
        let lo: SocketAddr = "127.0.0.1:0"
            .parse()
            .unwrap_or(SocketAddr::from(([127, 0, 0, 1], 0)));
        assert!(c.check(lo).is_ok());
        let v6: SocketAddr = SocketAddr::from((std::net::Ipv6Addr::LOCALHOST, 0));
        assert!(c.check(v6).is_ok());
        let any = SocketAddr::from(([0, 0, 0, 0], 8080));
        assert!(matches!(
            c.check(any),
            Err(ServeError::TokenRequired { .. })
        ));
        let with = ServeConfig {
            token: Some("s3cret".into()),
            ..ServeConfig::default()
        };
        assert!(with.check(any).is_ok());
        let blank = ServeConfig {
            token: Some("  ".into()),
            ..ServeConfig::default()
        };
        assert!(matches!(blank.check(lo), Err(ServeError::Config { .. })));
    }
}
