//! The web page, embedded in the binary: one HTML file, its script and its style sheet
//! (`server/assets/`), served as they are; no build step.

/// `GET /`.
pub(crate) const INDEX_HTML: &str = include_str!("../assets/index.html");
/// `GET /assets/app.js`.
pub(crate) const APP_JS: &str = include_str!("../assets/app.js");
/// `GET /assets/app.css`.
pub(crate) const APP_CSS: &str = include_str!("../assets/app.css");
