//! The protocol between the builder and the driver (`driver.py`), as types: each message is one
//! JSON line (a request's or an answer's doubles follow it as little-endian bytes). A line that
//! does not have a message's fields is refused as not the protocol's, instead of reading a
//! missing number as zero.

use serde::{Deserialize, Serialize};

/// The protocol this builder speaks; the driver greets with its own.
pub(crate) const PROTOCOL: u64 = 2;

/// The first line of every connection: the job's token and the driver's protocol.
#[derive(Debug, Deserialize)]
pub(crate) struct Greeting {
    pub hello: String,
    /// Kept as JSON: a wrong one is named in the refusal whatever it is.
    pub protocol: serde_json::Value,
}

/// `job.json`: where the driver connects back to, the token it greets with, the matrix and the
/// partitioner.
#[derive(Debug, Serialize)]
pub(crate) struct Job<'a> {
    pub host: &'a str,
    pub port: u16,
    pub token: &'a str,
    pub stiffness: &'a str,
    pub partitioner: &'a str,
}

/// A request; `doubles` counts the values that follow its line.
#[derive(Debug, Serialize)]
#[serde(tag = "op", rename_all = "lowercase")]
pub(crate) enum Request {
    /// x = K^-1 b for `columns` columns.
    Solve { columns: usize, doubles: usize },
    /// Each rank's peak memory.
    Stats { doubles: usize },
    /// The end of the job.
    Quit,
}

impl Request {
    /// The request's name, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Request::Solve { .. } => "\"solve\"",
            Request::Stats { .. } => "\"stats\"",
            Request::Quit => "\"quit\"",
        }
    }
}

/// What every answer carries: success or the driver's reason, and how many doubles follow.
#[derive(Debug, Deserialize)]
pub(crate) struct Answer {
    pub ok: bool,
    #[serde(default)]
    pub error: Option<String>,
    #[serde(default)]
    pub doubles: usize,
    /// Each rank's peak resident memory [MiB] (the answer to `stats`, and the first answer).
    #[serde(default)]
    pub peak_mib: Vec<f64>,
}

/// The first answer, once the factor is made: its figures, or why it could not be.
#[derive(Debug, Deserialize)]
pub(crate) struct Factored {
    pub ok: bool,
    #[serde(default)]
    pub error: Option<String>,
    #[serde(flatten)]
    pub figures: Option<FactorFigures>,
}

/// The driver's figures of a made factor.
#[derive(Debug, Clone, Deserialize)]
pub(crate) struct FactorFigures {
    pub ranks: usize,
    pub rows_per_rank: Vec<usize>,
    pub factor_entries: f64,
    pub seconds: FactorSeconds,
}

#[derive(Debug, Clone, Deserialize)]
pub(crate) struct FactorSeconds {
    pub load: f64,
    pub partition: f64,
    pub factor: f64,
}

/// The driver's reason, or that it gave none.
pub(crate) fn reason(error: &Option<String>) -> &str {
    error.as_deref().unwrap_or("no reason given")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_the_lines_the_driver_reads() {
        let solve = serde_json::to_string(&Request::Solve { columns: 3, doubles: 30 }).unwrap();
        assert_eq!(solve, r#"{"op":"solve","columns":3,"doubles":30}"#);
        assert_eq!(serde_json::to_string(&Request::Stats { doubles: 0 }).unwrap(), r#"{"op":"stats","doubles":0}"#);
        assert_eq!(serde_json::to_string(&Request::Quit).unwrap(), r#"{"op":"quit"}"#);
        let job = Job { host: "127.0.0.1", port: 5, token: "t", stiffness: "k.bin", partitioner: "current" };
        assert_eq!(
            serde_json::to_string(&job).unwrap(),
            r#"{"host":"127.0.0.1","port":5,"token":"t","stiffness":"k.bin","partitioner":"current"}"#
        );
    }

    #[test]
    fn the_first_answer_is_read_whole_or_refused() {
        let line = r#"{"ok": true, "ranks": 2, "rows_per_rank": [3, 4], "factor_entries": 1e3,
            "seconds": {"load": 0.1, "partition": 0.0, "factor": 0.5}, "peak_mib": [10, 11]}"#;
        let f: Factored = serde_json::from_str(line).unwrap();
        let figures = f.figures.expect("figures");
        assert_eq!((figures.ranks, figures.rows_per_rank.len(), figures.seconds.factor), (2, 2, 0.5));
        let failed: Factored = serde_json::from_str(r#"{"ok": false, "error": "singular"}"#).unwrap();
        assert!(!failed.ok && failed.figures.is_none() && reason(&failed.error) == "singular");
        // a success without its figures is not a factor with zero ranks
        let bare: Factored = serde_json::from_str(r#"{"ok": true, "ranks": 2}"#).unwrap();
        assert!(bare.figures.is_none());
    }

    #[test]
    fn an_answer_without_ok_is_not_the_protocol() {
        assert!(serde_json::from_str::<Answer>(r#"{"doubles": 4}"#).is_err());
        let a: Answer = serde_json::from_str(r#"{"ok": true, "doubles": 4, "columns": 1}"#).unwrap();
        assert_eq!((a.ok, a.doubles), (true, 4));
    }
}
