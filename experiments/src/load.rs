//! The machine's load average, recorded with every run: equal-time comparisons are only fair
//! when the load did not change under one method.

use std::fmt;

/// The 1-, 5- and 15-minute load averages of `/proc/loadavg` (Linux).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadAverage {
    /// Average run-queue length over the last minute.
    pub one: f64,
    /// Over the last five minutes.
    pub five: f64,
    /// Over the last fifteen minutes.
    pub fifteen: f64,
}

impl LoadAverage {
    /// Reads `/proc/loadavg`; `None` where it does not exist (not Linux) or cannot be parsed.
    #[must_use]
    pub fn read() -> Option<Self> {
        Self::parse(&std::fs::read_to_string("/proc/loadavg").ok()?)
    }

    /// Parses the first three fields of a `/proc/loadavg` line.
    ///
    /// # Example
    /// ```
    /// use experiments::LoadAverage;
    ///
    /// let load = LoadAverage::parse("1.83 1.43 0.83 3/250 4242").unwrap();
    /// assert_eq!((load.one, load.fifteen), (1.83, 0.83));
    /// assert_eq!(load.to_string(), "1.83 1.43 0.83");
    /// ```
    #[must_use]
    pub fn parse(line: &str) -> Option<Self> {
        let mut fields = line.split_whitespace().map(|f| f.parse::<f64>().ok());
        let (one, five, fifteen) = (fields.next()??, fields.next()??, fields.next()??);
        Some(Self { one, five, fifteen })
    }
}

impl fmt::Display for LoadAverage {
    /// `1.83 1.43 0.83`, as `/proc/loadavg` prints it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.2} {:.2} {:.2}", self.one, self.five, self.fifteen)
    }
}

/// `load` as text, `unknown` when it could not be read.
pub(crate) fn describe(load: Option<LoadAverage>) -> String {
    load.map_or_else(|| "unknown".to_owned(), |l| l.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_proc_loadavg_and_rejects_garbage() {
        assert_eq!(
            LoadAverage::parse("0.50 0.25 0.10 1/100 7\n"),
            Some(LoadAverage {
                one: 0.5,
                five: 0.25,
                fifteen: 0.1
            })
        );
        assert_eq!(LoadAverage::parse("0.5 x 0.1"), None);
        assert_eq!(LoadAverage::parse("0.5"), None);
        assert_eq!(describe(None), "unknown");
    }

    #[test]
    fn reads_on_linux() {
        if std::path::Path::new("/proc/loadavg").exists() {
            assert!(LoadAverage::read().is_some_and(|l| l.one >= 0.0));
        }
    }
}
