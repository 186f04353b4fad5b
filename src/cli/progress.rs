//! Progress bars on a terminal, nothing in a pipe or CI log.

use std::io::IsTerminal;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

use crate::job::Observer;

/// One bar (or spinner) per stage, on stderr, only when stderr is a terminal.
pub struct Bars {
    enabled: bool,
    current: Mutex<Option<ProgressBar>>,
}

impl Bars {
    pub fn new() -> Self {
        Self {
            enabled: std::io::stderr().is_terminal(),
            current: Mutex::new(None),
        }
    }
}

impl Observer for Bars {
    fn stage(&self, name: &str, work: u64) {
        if !self.enabled {
            return;
        }
        let Ok(mut current) = self.current.lock() else {
            return;
        };
        if let Some(bar) = current.take() {
            bar.finish_and_clear();
        }
        let bar = if work > 0 {
            let bar = ProgressBar::new(work);
            if let Ok(style) =
                ProgressStyle::with_template("{msg:>22} [{bar:40}] {pos}/{len} {elapsed}")
            {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        } else {
            ProgressBar::new_spinner()
        };
        bar.set_message(name.to_string());
        *current = Some(bar);
    }

    fn advance(&self) {
        if let Ok(current) = self.current.lock()
            && let Some(bar) = current.as_ref()
        {
            bar.inc(1);
        }
    }

    fn finish(&self) {
        if let Ok(mut current) = self.current.lock()
            && let Some(bar) = current.take()
        {
            bar.finish_and_clear();
        }
    }
}
