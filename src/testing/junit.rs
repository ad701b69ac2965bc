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
        if o.failure.is_none() && o.output.is_empty() {
            xml.push_str("/>\n");
            continue;
        }
        xml.push_str(">\n");
        if let Some(f) = &o.failure {
            xml.push_str(&format!(
                "      <failure message=\"{}\">{}</failure>\n",
                esc(&f.message),
                esc(&f.to_string())
            ));
        }
        // What the test printed, where CI systems show a test's output.
        if !o.output.is_empty() {
            xml.push_str(&format!(
                "      <system-out>{}</system-out>\n",
                esc(&o.output.join("\n"))
            ));
        }
        xml.push_str("    </testcase>\n");
    }
    xml.push_str("  </testsuite>\n</testsuites>\n");
    xml
}
