//! The CAN / CAN FD frame value the layout reads and writes.

/// One CAN or CAN FD frame with inline storage (no allocation).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CanFrame {
    /// Identifier without flags (11 bits, or 29 bits when `extended`).
    pub id: u32,
    /// 29-bit extended identifier.
    pub extended: bool,
    /// CAN FD frame (`##` in candump logs).
    pub fd: bool,
    /// FD flags as candump writes them: bit 0 BRS (bit-rate switch), bit 1 ESI (error state indicator).
    pub fd_flags: u8,
    /// Remote transmission request (classic only; data is empty, `len` is the requested length).
    pub remote: bool,
    pub(super) len: u8,
    pub(super) data: [u8; 64],
}

impl std::fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "CanFrame({:X}{}",
            self.id,
            if self.fd { "##" } else { "#" }
        )?;
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        write!(f, ")")
    }
}

/// Frame lengths CAN FD allows.
pub const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

impl CanFrame {
    /// A classic data frame; `None` when `data` is longer than 8 bytes or the identifier does not fit.
    pub fn classic(id: u32, extended: bool, data: &[u8]) -> Option<Self> {
        Self::build(id, extended, false, 0, data)
    }

    /// A CAN FD data frame with candump flags (bit 0 BRS, bit 1 ESI); `None` for a length FD does not allow.
    pub fn fd(id: u32, extended: bool, fd_flags: u8, data: &[u8]) -> Option<Self> {
        if !FD_LENGTHS.contains(&data.len()) {
            return None;
        }
        Self::build(id, extended, true, fd_flags, data)
    }

    /// A classic remote frame asking for `len` (0..=8) bytes.
    pub fn remote(id: u32, extended: bool, len: u8) -> Option<Self> {
        let mut f = Self::build(id, extended, false, 0, &[])?;
        if len > 8 {
            return None;
        }
        f.remote = true;
        f.len = len;
        Some(f)
    }

    fn build(id: u32, extended: bool, fd: bool, fd_flags: u8, data: &[u8]) -> Option<Self> {
        let id_ok = if extended {
            id <= 0x1FFF_FFFF
        } else {
            id <= 0x7FF
        };
        let max = if fd { 64 } else { 8 };
        if !id_ok || data.len() > max {
            return None;
        }
        let mut buf = [0u8; 64];
        buf[..data.len()].copy_from_slice(data);
        Some(Self {
            id,
            extended,
            fd,
            fd_flags,
            remote: false,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// Payload bytes (empty for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            &self.data[..usize::from(self.len)]
        }
    }

    /// Payload length, or the requested length for a remote frame.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// `true` when the frame carries no payload.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub(super) fn blank() -> Self {
        Self {
            id: 0,
            extended: false,
            fd: false,
            fd_flags: 0,
            remote: false,
            len: 0,
            data: [0; 64],
        }
    }
}
