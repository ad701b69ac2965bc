//! JUnit XML, for CI systems.

use super::TestOutcome;

/// JUnit XML for CI systems.
pub fn junit_xml(outcomes: &[TestOutcome]) -> String {
    fn esc(s: &str) -> String {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
            .replace('"', "&quot;")
    }
    let failures = outcomes.iter().filter(|o| o.failure.is_some()).count();
    let total: f64 = outcomes.iter().map(|o| o.duration.as_secs_f64()).sum();
    let mut xml = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites tests=\"{}\" failures=\"{failures}\" time=\"{total:.3}\">\n  <testsuite name=\"critterbox\" tests=\"{}\" failures=\"{failures}\" time=\"{total:.3}\">\n",
        outcomes.len(),
        outcomes.len()
    );
    for o in outcomes {
        xml.push_str(&format!(
            "    <testcase classname=\"{}\" name=\"{}\" time=\"{:.3}\"",
            esc(&o.case.file.display().to_string()),
            esc(if o.case.name.is_empty() {
                "(compile)"
            } else {
                &o.case.name
            }),
            o.duration.as_secs_f64()
        ));
        match &o.failure {
            None => xml.push_str("/>\n"),
            Some(f) => xml.push_str(&format!(
                ">\n      <failure message=\"{}\">{}</failure>\n    </testcase>\n",
                esc(&f.message),
                esc(&f.to_string())
            )),
        }
    }
    xml.push_str("  </testsuite>\n</testsuites>\n");
    xml
}
