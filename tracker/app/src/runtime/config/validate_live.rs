//! Range checks of the `[live]` table.

use super::{ConfigError, LiveConfig};
use drivers::evk4::biases::BiasOffsets;
use drivers::evk4::camera::SensorSettings;
use drivers::evk4::imx636;
use drivers::evk4::stream::StreamConfig;

/// The recording whose depth a `[live]` table uses (`depth_camera = "recording"`), or why there is none: the live
/// D435i driver is not there yet. `what` says what the caller does with it ("run", "record").
pub fn depth_recording<'a>(
    live: &'a LiveConfig,
    what: &str,
) -> Result<&'a std::path::Path, String> {
    live.depth_recording
        .as_deref()
        .filter(|_| live.depth_camera == "recording")
        .ok_or_else(|| {
            format!(
                "live.depth_camera = \"d435i\": the live D435i driver is not implemented yet; {what} with \
                 depth_camera = \"recording\" and depth_recording (the live EVK4 with a recording's depth frames)"
            )
        })
}

/// The sensor settings of a `[live]` table (biases and event-rate cap), or the key and why it is refused.
pub fn sensor_settings(live: &LiveConfig) -> Result<SensorSettings, String> {
    Ok(SensorSettings {
        biases: bias_offsets(live).map_err(|m| format!("live.biases: {m}"))?,
        erc_events_per_period: erc_target(live)
            .map_err(|m| format!("live.erc_events_per_second: {m}"))?,
    })
}

/// The USB data path of a `[live]` table: transfers in flight, their size, and the ring's slots.
pub fn stream_config(live: &LiveConfig) -> StreamConfig {
    let transfer_bytes = live.usb_transfer_kib * 1024;
    StreamConfig {
        transfers: live.usb_transfers,
        transfer_bytes,
        ring_slots: (live.ring_mib * 1024 * 1024)
            .div_ceil(transfer_bytes)
            .max(1),
    }
}

/// The bias offsets of a `[live]` table, checked against the sensor's ranges.
pub fn bias_offsets(live: &LiveConfig) -> Result<BiasOffsets, String> {
    BiasOffsets::from_named(live.biases.iter().map(|(k, v)| (k.as_str(), *v)))
        .map_err(|e| e.to_string())
}

/// The event-rate controller's target of a `[live]` table (`None`: no cap).
pub fn erc_target(live: &LiveConfig) -> Result<Option<u32>, String> {
    let rate = live.erc_events_per_second;
    if rate == 0.0 {
        return Ok(None);
    }
    imx636::erc_events_per_period(rate)
        .map(Some)
        .ok_or_else(|| {
            format!(
                "{rate} is out of range: 0 (no cap) or {} to {} events per second",
                1e6 / f64::from(imx636::ERC_REFERENCE_PERIOD_US),
                f64::from(imx636::ERC_MAX_EVENTS_PER_PERIOD) * 1e6
                    / f64::from(imx636::ERC_REFERENCE_PERIOD_US)
            )
        })
}

/// Checks a `[live]` table's values.
pub fn check_live(live: &LiveConfig, origin: &str) -> Result<(), ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Invalid {
        origin: origin.into(),
        key: format!("live.{key}"),
        message,
    };
    match live.depth_camera.as_str() {
        "d435i" => {}
        "recording" if live.depth_recording.is_none() => {
            return Err(bad(
                "depth_recording",
                "depth_camera = \"recording\" needs depth_recording (the recording whose depth frames to use)".into(),
            ));
        }
        "recording" => {}
        other => {
            return Err(bad(
                "depth_camera",
                format!("`{other}` is not supported (supported: d435i, recording)"),
            ));
        }
    }
    bias_offsets(live).map_err(|m| bad("biases", m))?;
    erc_target(live).map_err(|m| bad("erc_events_per_second", m))?;
    let ranges: [(&str, usize, usize, usize); 3] = [
        ("usb_transfers", live.usb_transfers, 1, 256),
        ("usb_transfer_kib", live.usb_transfer_kib, 4, 4096),
        ("ring_mib", live.ring_mib, 1, 4096),
    ];
    for (key, value, min, max) in ranges {
        if !(min..=max).contains(&value) {
            return Err(bad(key, format!("{value} is out of range: {min}..={max}")));
        }
    }
    if live.reconnect_ms == 0
        || live.reconnect_max_ms < live.reconnect_ms
        || live.reconnect_max_ms > 600_000
    {
        return Err(bad(
            "reconnect_max_ms",
            format!(
                "reconnect_ms = {} and reconnect_max_ms = {}: need 0 < reconnect_ms <= reconnect_max_ms <= 600000",
                live.reconnect_ms, live.reconnect_max_ms
            ),
        ));
    }
    Ok(())
}
