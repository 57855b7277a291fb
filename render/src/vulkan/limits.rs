//! The device limits every buffer and dispatch stays within: `maxStorageBufferRange` (the
//! most bytes one storage binding may cover), `maxMemoryAllocationSize` (the largest buffer)
//! and `maxComputeWorkGroupCount`. Many drivers (lavapipe, Intel, several AMD and mobile ones)
//! bind at most 2²⁷ bytes; the H200 binds 2³² − 1.
//!
//! [`HostBuffer::new`](super::buffer::HostBuffer::new) refuses a buffer above the allocation
//! limit and every descriptor write refuses a range above the storage limit
//! ([`GpuError::Limit`]), so nothing is ever bound past a limit; the passes size what they
//! allocate to the limits instead (the shadow-ray queue holds what fits and the rest is traced
//! in place, the world has one buffer per region, the viewport lowers its internal size).
//!
//! `VOXBRICK_MAX_STORAGE_RANGE` and `VOXBRICK_MAX_ALLOCATION` (bytes, or with a K / M / G
//! suffix: `16M`) lower the limits on any machine, so tests exercise the sized-down paths
//! where the real limits are large. They never raise a limit.

use super::GpuError;
use ash::vk;

/// Environment variable capping the storage range.
pub const STORAGE_RANGE_ENV: &str = "VOXBRICK_MAX_STORAGE_RANGE";
/// Environment variable capping the allocation size.
pub const ALLOCATION_ENV: &str = "VOXBRICK_MAX_ALLOCATION";

/// The limits in force (the device's, lowered by the environment's caps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceLimits {
    /// Most bytes one storage-buffer binding covers.
    pub storage_range: u64,
    /// Largest single buffer in bytes.
    pub allocation: u64,
    /// Most workgroups of one dispatch along x, y and z.
    pub groups: [u32; 3],
    /// Whether an environment cap lowered a limit.
    pub capped: bool,
}

impl DeviceLimits {
    /// Limits with no cap (tests of the sizing logic).
    pub fn new(storage_range: u64, allocation: u64, groups: [u32; 3]) -> Self {
        Self {
            storage_range,
            allocation,
            groups,
            capped: false,
        }
    }

    /// The device's limits, lowered by the environment's caps.
    pub fn read(instance: &ash::Instance, physical: vk::PhysicalDevice) -> Result<Self, GpuError> {
        let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
        // SAFETY: a plain query with a valid output chain (Vulkan 1.1 core).
        let limits = unsafe {
            let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
            instance.get_physical_device_properties2(physical, &mut props);
            props.properties.limits
        };
        let device = Self::new(
            u64::from(limits.max_storage_buffer_range),
            maintenance3.max_memory_allocation_size,
            limits.max_compute_work_group_count,
        );
        Ok(device.capped_by(
            cap_from_env(STORAGE_RANGE_ENV)?,
            cap_from_env(ALLOCATION_ENV)?,
        ))
    }

    /// These limits lowered to the caps given (a cap never raises a limit).
    pub fn capped_by(mut self, range: Option<u64>, allocation: Option<u64>) -> Self {
        if let Some(r) = range.filter(|&r| r < self.storage_range) {
            self.storage_range = r;
            self.capped = true;
        }
        if let Some(a) = allocation.filter(|&a| a < self.allocation) {
            self.allocation = a;
            self.capped = true;
        }
        self
    }

    /// The most bytes a buffer that is bound whole may have: the smaller of the two limits.
    pub fn bound_buffer(&self) -> u64 {
        self.storage_range.min(self.allocation)
    }

    /// The most elements of `bytes` each a buffer bound whole may hold.
    pub fn elements(&self, bytes: u64) -> u64 {
        self.bound_buffer() / bytes.max(1)
    }

    /// The largest image of `size`'s aspect whose buffers of `bytes_per_pixel` fit the limits
    /// (and whose 8 × 8 workgroups do): `size` itself when it fits.
    pub fn fit_image(&self, size: (u32, u32), bytes_per_pixel: u64) -> (u32, u32) {
        let (w, h) = (u64::from(size.0.max(1)), u64::from(size.1.max(1)));
        let most = self.elements(bytes_per_pixel).max(1);
        let side = |g: u32| u64::from(g).saturating_mul(8);
        let mut scale = ((most as f64) / (w * h) as f64).sqrt().min(1.0);
        scale = scale
            .min(side(self.groups[0]) as f64 / w as f64)
            .min(side(self.groups[1]) as f64 / h as f64);
        let mut fit = (
            ((w as f64 * scale).floor() as u64).max(1),
            ((h as f64 * scale).floor() as u64).max(1),
        );
        // Rounding may leave one pixel too many: shrink the longer side until it fits.
        while fit.0 * fit.1 > most && (fit.0 > 1 || fit.1 > 1) {
            if fit.0 >= fit.1 {
                fit.0 -= 1
            } else {
                fit.1 -= 1
            }
        }
        (fit.0 as u32, fit.1 as u32)
    }

    /// Refuses an image whose buffers of `bytes_per_pixel` (each bound whole) or whose 8 × 8
    /// workgroups pass a limit.
    pub fn check_image(
        &self,
        what: &str,
        size: (u32, u32),
        bytes_per_pixel: u64,
    ) -> Result<(), GpuError> {
        let bytes = u64::from(size.0) * u64::from(size.1) * bytes_per_pixel;
        let what = format!("{what} of {} × {}", size.0, size.1);
        self.check_allocation(&what, bytes)?;
        self.check_binding(&what, bytes)?;
        self.check_groups(&what, [size.0.div_ceil(8), size.1.div_ceil(8), 1])
    }

    /// Refuses a buffer above the allocation limit.
    pub fn check_allocation(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        if bytes > self.allocation {
            return Err(GpuError::Limit {
                what: what.to_string(),
                bytes,
                limit: "maxMemoryAllocationSize",
                max: self.allocation,
            });
        }
        Ok(())
    }

    /// Refuses a storage binding above the storage range limit.
    pub fn check_binding(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        if bytes > self.storage_range {
            return Err(GpuError::Limit {
                what: what.to_string(),
                bytes,
                limit: "maxStorageBufferRange",
                max: self.storage_range,
            });
        }
        Ok(())
    }

    /// Refuses a dispatch of more workgroups than the device runs along an axis.
    pub fn check_groups(&self, what: &str, groups: [u32; 3]) -> Result<(), GpuError> {
        for axis in 0..3 {
            if groups[axis] > self.groups[axis] {
                return Err(GpuError::Limit {
                    what: format!("{what} (workgroups along {})", ["x", "y", "z"][axis]),
                    bytes: u64::from(groups[axis]),
                    limit: "maxComputeWorkGroupCount",
                    max: u64::from(self.groups[axis]),
                });
            }
        }
        Ok(())
    }
}

/// A byte count: digits with an optional K, M or G suffix (binary multiples).
pub fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let (digits, shift) = match t.char_indices().last()? {
        (i, 'k' | 'K') => (&t[..i], 10),
        (i, 'm' | 'M') => (&t[..i], 20),
        (i, 'g' | 'G') => (&t[..i], 30),
        _ => (t, 0),
    };
    let n: u64 = digits.trim().parse().ok()?;
    (n > 0).then_some(n)?.checked_mul(1 << shift)
}

fn cap_from_env(name: &'static str) -> Result<Option<u64>, GpuError> {
    match std::env::var(name) {
        Err(_) => Ok(None),
        Ok(v) => parse_bytes(&v).map(Some).ok_or_else(|| {
            GpuError::BadSetting(format!(
                "{name}={v:?} is not a byte count (digits with an optional K, M or G suffix, above 0)"
            ))
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_parse_with_suffixes_and_refuse_nonsense() {
        assert_eq!(parse_bytes("4096"), Some(4096));
        assert_eq!(parse_bytes("16M"), Some(16 << 20));
        assert_eq!(parse_bytes(" 64m "), Some(64 << 20));
        assert_eq!(parse_bytes("2G"), Some(2 << 30));
        assert_eq!(parse_bytes("1k"), Some(1024));
        for bad in ["", "M", "0", "-5", "12X", "1.5M", "99999999999999999999G"] {
            assert_eq!(parse_bytes(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn caps_only_lower_limits_and_checks_name_the_limit() {
        let device = DeviceLimits::new(1 << 27, 1 << 31, [65535; 3]);
        let same = device.capped_by(Some(1 << 30), None);
        assert_eq!(same, device);
        let capped = device.capped_by(Some(16 << 20), Some(64 << 20));
        assert!(capped.capped);
        assert_eq!(capped.storage_range, 16 << 20);
        assert_eq!(capped.allocation, 64 << 20);
        assert_eq!(capped.bound_buffer(), 16 << 20);
        assert_eq!(capped.elements(48), (16 << 20) / 48);
        assert!(capped.check_binding("x", 16 << 20).is_ok());
        let e = capped
            .check_binding("shadow rays", (16 << 20) + 4)
            .unwrap_err();
        assert!(e.to_string().contains("maxStorageBufferRange"), "{e}");
        assert!(e.to_string().contains("shadow rays"), "{e}");
        assert!(capped.check_allocation("world", 65 << 20).is_err());
        assert!(capped.check_groups("trace", [65535, 1, 1]).is_ok());
        let e = capped
            .check_groups("shadow pass", [65536, 1, 1])
            .unwrap_err();
        assert!(e.to_string().contains("maxComputeWorkGroupCount"), "{e}");
    }

    #[test]
    fn images_are_fitted_within_the_limits_keeping_their_aspect() {
        let limits = DeviceLimits::new(16 << 20, 64 << 20, [65535; 3]);
        assert_eq!(limits.fit_image((640, 360), 32), (640, 360));
        for size in [(1920, 1080), (3840, 2160), (16384, 16384), (7, 100_000)] {
            let fit = limits.fit_image(size, 32);
            assert!(
                u64::from(fit.0) * u64::from(fit.1) * 32 <= 16 << 20,
                "{size:?} → {fit:?}"
            );
            assert!(limits.check_image("image", fit, 32).is_ok(), "{fit:?}");
            assert!(limits.check_image("image", size, 32).is_err(), "{size:?}");
            let (a, b) = (size.0 as f64 / size.1 as f64, fit.0 as f64 / fit.1 as f64);
            assert!(
                (a / b - 1.0).abs() < 0.02 || fit.0 <= 1 || fit.1 <= 2,
                "{size:?} → {fit:?}"
            );
        }
        // The workgroup count bounds a side too.
        let narrow = DeviceLimits::new(1 << 40, 1 << 40, [16, 65535, 65535]);
        assert_eq!(narrow.fit_image((1024, 64), 16).0, 128);
    }
}
