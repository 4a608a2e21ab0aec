//! The Markdown report: sections, tables, images, the machine and the settings.

use super::machine::Machine;
use super::suite::{Suite, NO_REPEAT_MS};

/// A Markdown table.
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(header: &[&str]) -> Self {
        Table {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: vec![],
        }
    }

    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    fn markdown(&self) -> String {
        let mut s = format!(
            "| {} |\n|{}\n",
            self.header.join(" | "),
            "---|".repeat(self.header.len())
        );
        for r in &self.rows {
            s.push_str(&format!("| {} |\n", r.join(" | ")));
        }
        s
    }
}

/// The report being written.
#[derive(Clone)]
pub struct Report {
    md: String,
}

impl Report {
    pub fn new(suite: &Suite, m: &Machine) -> Self {
        let mut md = format!("# sightline benchmark report — suite `{}`\n\n", suite.name);
        md.push_str(&format!(
            "Machine: {} — {} cores, {:.1} GiB, {}. Revision `{}`. Build: {}.\n\n",
            m.cpu,
            m.cores,
            m.memory_gib,
            m.os,
            m.git_revision,
            if cfg!(debug_assertions) {
                "dev profile (opt-level 2, debug assertions on: timings are pessimistic)"
            } else {
                "release"
            }
        ));
        md.push_str(&format!(
            "Settings: seed {}, {} cells per setting, timings are the median of {} runs per cell (a run over {} ms is not repeated; single thread per cell); ground truth with the default `TruthOptions`. Raw figures: `raw.json`.\n\n",
            suite.seed,
            suite.cells_per_setting,
            suite.timing_repeats,
            NO_REPEAT_MS
        ));
        Report { md }
    }

    pub fn section(&mut self, title: &str) {
        self.md.push_str(&format!("## {title}\n\n"));
    }

    pub fn para(&mut self, text: &str) {
        self.md.push_str(text);
        self.md.push_str("\n\n");
    }

    pub fn table(&mut self, t: &Table) {
        self.md.push_str(&t.markdown());
        self.md.push('\n');
    }

    pub fn image(&mut self, file: &str, alt: &str) {
        self.md.push_str(&format!("![{alt}]({file})\n\n"));
    }

    pub fn notes(&mut self, notes: &[String]) {
        if notes.is_empty() {
            return;
        }
        self.section("Notes");
        for n in notes {
            self.md.push_str(&format!("- {n}\n"));
        }
        self.md.push('\n');
    }

    /// The closing line: the whole suite's wall time and each experiment's.
    /// `done` is false for a report written while experiments remain.
    pub fn footer(&mut self, seconds: f64, parts: &[(&str, f64)], done: bool) {
        let parts: Vec<String> = parts
            .iter()
            .map(|(name, s)| format!("{name} {s:.0} s"))
            .collect();
        let what = if done {
            "Suite ran in"
        } else {
            "Partial report (still running):"
        };
        self.md.push_str(&format!(
            "---\n{what} {seconds:.0} s ({}).\n",
            parts.join(", ")
        ));
    }

    pub fn markdown(&self) -> String {
        self.md.clone()
    }
}
