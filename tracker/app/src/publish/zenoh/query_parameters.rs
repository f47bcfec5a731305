//! The parameters of a pose query (`<prefix>/<object>/pose_at?t_us=T`): which time is asked for. Plain `std`, so
//! the fuzz target compiles this file alone.

/// The time a query's parameters name, on the camera clock in microseconds: exactly one of `t_us` (camera clock,
/// microseconds) or `stamp_ns` (ROS time as in the pose topic's `header.stamp`, nanoseconds; the camera time is
/// `(stamp_ns - ros_time_offset_ns) / 1000`, rounded down), as decimal integers. The parameters are zenoh's
/// selector parameters: `key=value` pairs separated by `;` or `&`.
pub fn requested_time(parameters: &str, ros_time_offset_ns: i64) -> Result<i64, String> {
    let mut t_us = None;
    let mut stamp_ns = None;
    for pair in parameters.split([';', '&']).filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        let slot = match key {
            "t_us" => &mut t_us,
            "stamp_ns" => &mut stamp_ns,
            other => {
                return Err(format!(
                    "unknown parameter `{other}`: give t_us=<camera time, us> or stamp_ns=<ROS time, ns>"
                ));
            }
        };
        if slot.is_some() {
            return Err(format!("parameter `{key}` given twice"));
        }
        let v: i64 = value
            .parse()
            .map_err(|_| format!("`{key}` = `{value}` is not a whole number"))?;
        *slot = Some(v);
    }
    match (t_us, stamp_ns) {
        (Some(t), None) => Ok(t),
        (None, Some(s)) => s
            .checked_sub(ros_time_offset_ns)
            .map(|ns| ns.div_euclid(1000))
            .ok_or_else(|| format!("stamp_ns {s} is out of range")),
        (Some(_), Some(_)) => Err("give t_us or stamp_ns, not both".into()),
        (None, None) => Err(
            "no time given: ask for `<key>?t_us=<camera time, us>` or `<key>?stamp_ns=<ROS time, ns>`".into(),
        ),
    }
}
