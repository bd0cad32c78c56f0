//! What the program runs on, for the benchmark reports: a performance figure means little without the
//! CPU it was measured on (a ratio measured on one CPU does not carry to another).

/// The CPU's name as the operating system gives it, with its family and model numbers (virtual
/// machines often report only a generic name such as "Intel(R) Xeon(R) Processor"), and the number of
/// logical CPUs this process may use: `Intel(R) Xeon(R) Processor (family 6, model 167), 2 logical
/// CPUs`. Where the name cannot be read (not Linux), the architecture stands in for it.
pub fn cpu() -> String {
    let logical = std::thread::available_parallelism().map_or(1, |n| n.get());
    let name = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| cpu_name(&text))
        .unwrap_or_else(|| format!("unknown {} CPU", std::env::consts::ARCH));
    format!("{name}, {logical} logical CPUs")
}

/// The first processor's `model name` in `/proc/cpuinfo`'s text, with its `cpu family` and `model`.
fn cpu_name(cpuinfo: &str) -> Option<String> {
    let processor = cpuinfo.split("\n\n").next()?;
    let field = |key: &str| {
        processor.lines().find_map(|line| {
            let (k, v) = line.split_once(':')?;
            (k.trim() == key).then(|| v.trim().to_string())
        })
    };
    let name = field("model name")?;
    Some(match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => format!("{name} (family {family}, model {model})"),
        _ => name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_processors_name_family_and_model() {
        let text = "processor\t: 0\nvendor_id\t: GenuineIntel\ncpu family\t: 6\nmodel\t\t: 167\n\
                    model name\t: Intel(R) Xeon(R) Processor\nstepping\t: 1\n\nprocessor\t: 1\n\
                    model name\t: Other\n";
        assert_eq!(
            cpu_name(text).as_deref(),
            Some("Intel(R) Xeon(R) Processor (family 6, model 167)")
        );
        // ARM's cpuinfo has no model name: the caller falls back to the architecture.
        assert_eq!(cpu_name("processor\t: 0\nBogoMIPS\t: 50.00\n"), None);
        assert_eq!(cpu_name("model name\t: Some CPU\n").as_deref(), Some("Some CPU"));
    }
}
