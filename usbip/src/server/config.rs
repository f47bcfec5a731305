//! How the served device is named on the wire.

use crate::protocol::{BusId, SysfsPath};

/// The bus position the device is exported under.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServerConfig {
    /// Bus id the host imports by (e.g. `"1-1"`); an import of any other is refused with status 1.
    pub busid: BusId,
    /// Sysfs path reported in the device record; informational.
    pub path: SysfsPath,
    /// Bus number reported in the device record.
    pub busnum: u32,
    /// Device number reported in the device record.
    pub devnum: u32,
}

impl ServerConfig {
    /// The device at `busid`, bus 1, device 2, with a path naming the emulator.
    pub fn new(busid: BusId) -> Self {
        let path =
            SysfsPath::new(&format!("/sys/devices/eventtrack6d/{busid}")).unwrap_or_default();
        Self {
            busid,
            path,
            busnum: 1,
            devnum: 2,
        }
    }
}
