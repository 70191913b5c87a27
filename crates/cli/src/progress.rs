//! Progress bars for long runs (silent when stderr is not a terminal, so CI logs stay clean).

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar over `len` steps with a short label.
pub(crate) fn bar(len: u64, label: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    let style = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta})")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    pb.set_style(style);
    pb.set_message(label.to_string());
    pb
}
