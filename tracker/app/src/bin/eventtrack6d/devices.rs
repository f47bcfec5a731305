//! `eventtrack6d devices`: the connected cameras the live source can use.

use anyhow::Result;
use clap::Args;
use drivers::evk4::discovery::list_cameras;

/// List the connected event cameras (Prophesee EVK4 and its OEM variants) the live source can open.
///
/// For each: model, USB ids, bus and address, link speed, serial number, firmware release and sensor, read by
/// opening the camera for a moment (a camera another program has open shows as busy). A camera this user may not
/// open is listed with the udev rule to install (config/99-eventtrack6d.rules). Put the serial into `[live]
/// event_serial` to pick one of several cameras. Exits with an error when USB itself is unusable (no usbfs).
#[derive(Debug, Args)]
pub struct DevicesArgs {
    /// Print JSON (one object per camera) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: &DevicesArgs) -> Result<()> {
    let context = rusb::Context::new()
        .map_err(|e| anyhow::anyhow!("USB is not usable on this machine: {e}"))?;
    let cameras = list_cameras(&context)?;
    if args.json {
        let list: Vec<serde_json::Value> = cameras
            .iter()
            .map(|c| {
                serde_json::json!({
                    "model": c.model, "vendor_id": format!("{:04x}", c.vendor_id),
                    "product_id": format!("{:04x}", c.product_id), "bus": c.bus, "address": c.address,
                    "speed": c.speed, "serial": c.serial, "firmware": c.firmware, "sensor": c.sensor,
                    "usable": c.problem.is_none(), "problem": c.problem,
                })
            })
            .collect();
        println!("{}", serde_json::to_string_pretty(&list)?);
        return Ok(());
    }
    if cameras.is_empty() {
        println!(
            "no event camera found (supported: Prophesee EVK4, USB 04b4:00f4, 04b4:00f5, 31f7:0003, 31f7:0004, 1409:8e00)"
        );
        return Ok(());
    }
    for c in &cameras {
        println!(
            "{} {:04x}:{:04x} bus {:03} address {:03}, {}: serial {}, firmware {}, sensor {}",
            c.model,
            c.vendor_id,
            c.product_id,
            c.bus,
            c.address,
            c.speed,
            c.serial.as_deref().unwrap_or("?"),
            c.firmware.as_deref().unwrap_or("?"),
            c.sensor.as_deref().unwrap_or("?"),
        );
        match &c.problem {
            None => println!("  usable: yes"),
            Some(p) => println!("  usable: no: {p}"),
        }
    }
    Ok(())
}
