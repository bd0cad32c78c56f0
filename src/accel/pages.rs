//! Large read-mostly arrays on transparent huge pages (Linux).
//!
//! A wide BVH of the 871k-triangle dragon is about 50 MB of nodes and triangle blocks, and incoherent
//! rays visit it all over: with 4 KB pages that is some 12,000 pages, many more than the TLB maps, so a
//! diffuse ray's node visits also walk the page table. 2 MB pages map the whole structure in a few
//! dozen TLB entries (Embree's allocator asks for them too). The kernel gives them to a range advised
//! with `madvise(MADV_HUGEPAGE)` when it is first touched, so the array is copied into a fresh
//! allocation advised before it is written. This is advice only: where transparent huge pages are off
//! (`/sys/kernel/mm/transparent_hugepage/enabled` says `never`), or on another system, nothing changes
//! but the copy.

/// The size of an x86-64 huge page.
const HUGE: usize = 2 << 20;

/// `v`, moved to memory advised for huge pages when it spans at least two of them (smaller arrays fit
/// the TLB anyway and are returned as they are).
pub fn on_huge_pages<T: Copy>(v: Vec<T>) -> Vec<T> {
    if size_of_val(v.as_slice()) < 2 * HUGE || !cfg!(target_os = "linux") {
        return v;
    }
    let mut out = with_capacity_on_huge_pages(v.len());
    out.extend_from_slice(&v);
    out
}

/// An empty vector with room for `n` elements, its memory advised for huge pages when it spans at least
/// two of them: filled without growing, it is on huge pages without a copy.
pub fn with_capacity_on_huge_pages<T>(n: usize) -> Vec<T> {
    let out = Vec::with_capacity(n);
    let bytes = n * size_of::<T>();
    if bytes >= 2 * HUGE {
        advise(out.as_ptr() as usize, bytes);
    }
    out
}

/// Advises the whole huge pages inside `[start, start + bytes)` for huge pages.
#[cfg(target_os = "linux")]
fn advise(start: usize, bytes: usize) {
    let (lo, hi) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
    if hi > lo {
        // SAFETY: `[lo, hi)` lies inside an allocation the caller owns and has not yet written;
        // madvise gives the kernel advice about the range and changes none of its contents. A refusal
        // (THP not built into the kernel) only leaves the default pages.
        unsafe { libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: usize, _bytes: usize) {}

#[cfg(test)]
mod tests {
    use super::{HUGE, on_huge_pages};

    #[test]
    fn contents_survive_the_move() {
        let small: Vec<u32> = (0..1000).collect();
        assert_eq!(on_huge_pages(small.clone()), small);
        let large: Vec<u64> = (0..(3 * HUGE / 8) as u64)
            .map(|i| i.wrapping_mul(0x9e37_79b9))
            .collect();
        assert_eq!(on_huge_pages(large.clone()), large);
    }
}
