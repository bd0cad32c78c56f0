//! How much memory a frame needs, and whether this process can have it: checked before anything is
//! allocated, so that a resolution too large for the machine is refused with the size it would need,
//! instead of aborting on a failed allocation (or being killed by the kernel) halfway through a render.

use std::fmt::Write;

/// Bytes a pixel takes at the peak of a render written to a file: the passes' `f64` sums (24), the film
/// of their mean (12), the 8-bit image (3) and the encoder's copy of it (3).
pub const BYTES_PER_PIXEL: u64 = 42;

/// Bytes a pixel takes more when the render counts steps ([`super::Options::count_steps`]): its rays
/// and steps in the pass (104) and summed over the passes over the whole frame, even for a part (104),
/// and a heatmap's counts (4), image (3) and raw film with the encoder's copy (24).
pub const COUNTED_BYTES_PER_PIXEL: u64 = 239;

/// The bytes a pixel needs, counting steps or not.
fn per_pixel(counted: bool) -> u64 {
    BYTES_PER_PIXEL + if counted { COUNTED_BYTES_PER_PIXEL } else { 0 }
}

/// The bytes a `width` × `height` frame needs at its peak, counting steps or not.
pub fn frame_bytes(width: u32, height: u32, counted: bool) -> u64 {
    u64::from(width) * u64::from(height) * per_pixel(counted)
}

/// Bytes a pixel takes at the peak of `merge`: the frame's `f64` sums and pass counts (28), the film of
/// their mean (12), the 8-bit image and the encoder's copy (6), and the one part read at a time, which
/// may cover the whole frame (28).
pub const MERGE_BYTES_PER_PIXEL: u64 = 74;

/// Refuses a frame that needs more memory than this process can still use ([`available`]); a
/// frame whose need cannot be compared (no figure to read) is let through. `parts` says whether the
/// command can render the frame in parts (`render --tiles`), which the advice then offers.
pub fn check(width: u32, height: u32, counted: bool, parts: bool) -> Result<(), String> {
    check_against(width, height, counted, parts, available())
}

/// [`check`] against `available` bytes.
pub fn check_against(
    width: u32,
    height: u32,
    counted: bool,
    parts: bool,
    available: Option<u64>,
) -> Result<(), String> {
    let (what, instead) = match (counted, parts) {
        (true, _) => (
            ", counting steps",
            "lower the resolution, or leave out --counters and --heatmap",
        ),
        (false, true) => ("", "lower the resolution, or render it in parts (--tiles K/N)"),
        (false, false) => ("", "lower the resolution"),
    };
    let need = frame_bytes(width, height, counted);
    let what = format!(
        "a {width}x{height} frame needs {} ({} bytes a pixel{what})",
        gib(need),
        per_pixel(counted)
    );
    refuse(need, &what, instead, available)
}

/// Refuses to merge the parts of a `width` × `height` frame where this process cannot have the
/// memory it takes ([`MERGE_BYTES_PER_PIXEL`]).
pub fn check_merge(width: u32, height: u32) -> Result<(), String> {
    let need = u64::from(width) * u64::from(height) * MERGE_BYTES_PER_PIXEL;
    let what = format!(
        "merging a {width}x{height} frame needs {} ({MERGE_BYTES_PER_PIXEL} bytes a pixel)",
        gib(need)
    );
    refuse(
        need,
        &what,
        "merge on a machine with more memory free",
        available(),
    )
}

/// `Err` where `need` bytes are more than `available`: "`what` and only N GiB is available: `instead`".
fn refuse(need: u64, what: &str, instead: &str, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(have) if need > have => Err(format!("{what} and only {} is available: {instead}", gib(have))),
        _ => Ok(()),
    }
}

/// Refuses a skybox whose faces take `sky` bytes to load ([`crate::render::env::CubeMap::bytes`]) when,
/// with a frame's `frame` bytes ([`frame_bytes`], or 0 where the frame is not checked), they need more
/// than this process can still use ([`available`]).
pub fn check_skybox(sky: u64, frame: u64) -> Result<(), String> {
    check_skybox_against(sky, frame, available())
}

/// [`check_skybox`] against `available` bytes.
pub fn check_skybox_against(sky: u64, frame: u64, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(have) if sky.saturating_add(frame) > have => Err(format!(
            "the skybox's faces need {} to load, beside the frame's {}, and only {} is available: use \
             smaller faces",
            gib(sky),
            gib(frame),
            gib(have)
        )),
        _ => Ok(()),
    }
}

/// `bytes` in GiB with two decimals.
fn gib(bytes: u64) -> String {
    let mut s = String::new();
    let _ = write!(s, "{:.2} GiB", bytes as f64 / (1u64 << 30) as f64);
    s
}

/// The memory this process can still use: the least of the system's available memory
/// (`MemAvailable`), its control group's limit less its usage (cgroup v2), and its address-space limit
/// (`ulimit -v`) less its address space. `None` where none of them can be read (other systems than
/// Linux).
pub fn available() -> Option<u64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let meminfo = read("/proc/meminfo").and_then(|s| field_kib(&s, "MemAvailable:"));
    let rlimit = read("/proc/self/limits")
        .and_then(|s| address_space_limit(&s))
        .zip(read("/proc/self/status").and_then(|s| field_kib(&s, "VmSize:")))
        .map(|(limit, used)| limit.saturating_sub(used));
    let cgroup = read("/proc/self/cgroup").and_then(|c| {
        let dir = format!("/sys/fs/cgroup{}", c.lines().find_map(|l| l.strip_prefix("0::"))?);
        let max = read(&format!("{dir}/memory.max"))?.trim().parse::<u64>().ok()?;
        let current = read(&format!("{dir}/memory.current"))?
            .trim()
            .parse::<u64>()
            .ok()?;
        Some(max.saturating_sub(current))
    });
    [meminfo, rlimit, cgroup].into_iter().flatten().min()
}

/// A `Name:   N kB` line of `/proc/meminfo` or `/proc/self/status`, in bytes.
fn field_kib(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// The soft limit of `Max address space` in `/proc/self/limits` (`None` when unlimited).
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_a_frame_larger_than_what_is_available_with_both_sizes() {
        // 16384 x 16384 x 42 bytes = 10.5 GiB exactly.
        assert_eq!(frame_bytes(16384, 16384, false), 11_274_289_152);
        assert_eq!(
            check_against(16384, 16384, false, true, Some(4 << 30)).unwrap_err(),
            "a 16384x16384 frame needs 10.50 GiB (42 bytes a pixel) and only 4.00 GiB is available: \
             lower the resolution, or render it in parts (--tiles K/N)"
        );
        assert!(check_against(16384, 16384, false, true, Some(11_274_289_152)).is_ok());
        assert!(check_against(16384, 16384, false, true, None).is_ok());
        assert!(check_against(1920, 1080, false, true, Some(1 << 30)).is_ok());
        // Counting steps: 42 + 239 = 281 bytes a pixel; 4096 x 4096 of them is 4.39 GiB.
        assert_eq!(frame_bytes(4096, 4096, true), 4096 * 4096 * 281);
        assert_eq!(
            check_against(4096, 4096, true, true, Some(4 << 30)).unwrap_err(),
            "a 4096x4096 frame needs 4.39 GiB (281 bytes a pixel, counting steps) and only 4.00 GiB is \
             available: lower the resolution, or leave out --counters and --heatmap"
        );
        assert!(check_against(4096, 4096, false, true, Some(4 << 30)).is_ok());
        // A command that cannot render in parts (bench) is not told to.
        assert_eq!(
            check_against(16384, 16384, false, false, Some(4 << 30)).unwrap_err(),
            "a 16384x16384 frame needs 10.50 GiB (42 bytes a pixel) and only 4.00 GiB is available: \
             lower the resolution"
        );
    }

    #[test]
    fn refuses_a_skybox_that_does_not_fit_beside_the_frame() {
        let (sky, frame) = (3 << 30, 1 << 29);
        assert_eq!(
            check_skybox_against(sky, frame, Some(3 << 30)).unwrap_err(),
            "the skybox's faces need 3.00 GiB to load, beside the frame's 0.50 GiB, and only 3.00 GiB \
             is available: use smaller faces"
        );
        assert!(check_skybox_against(sky, frame, Some(sky + frame)).is_ok());
        assert!(check_skybox_against(sky, frame, None).is_ok());
    }

    #[test]
    fn reads_the_proc_files() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   3000000 kB\n";
        assert_eq!(field_kib(meminfo, "MemAvailable:"), Some(3_072_000_000));
        assert_eq!(field_kib(meminfo, "VmSize:"), None);
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         4096000000           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(4_096_000_000));
        let unlimited = "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_limit(unlimited), None);
    }

    /// On Linux, where the test suite runs, at least `/proc/meminfo` is there to read.
    #[test]
    #[cfg(target_os = "linux")]
    fn this_machine_has_a_figure() {
        let have = available().expect("a figure on Linux");
        assert!(have > 1 << 20, "{have} bytes available");
    }
}
