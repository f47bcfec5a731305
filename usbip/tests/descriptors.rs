//! The descriptor builder's bytes at high speed and SuperSpeed, and its limits.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use usbip::descriptors::{
    DescriptorError, DeviceDescriptors, DeviceSpec, EndpointSpec, InterfaceSpec, Speed,
};

fn spec(speed: Speed) -> DeviceSpec {
    DeviceSpec::new(speed, 0x04b4, 0x00f5)
        .with_strings("Acme", "Cam", "0001")
        .with_interface(InterfaceSpec {
            class: 0xff,
            name: Some("Stream".into()),
            endpoints: vec![
                EndpointSpec::bulk_in(1).with_max_burst(15),
                EndpointSpec::bulk_out(2),
            ],
            ..InterfaceSpec::default()
        })
}

#[test]
fn high_speed_device_configuration_and_strings() {
    let d = DeviceDescriptors::build(&spec(Speed::High)).unwrap();
    assert_eq!(
        d.device(),
        [
            18, 1, 0x00, 0x02, 0, 0, 0, 64, 0xb4, 0x04, 0xf5, 0x00, 0x00, 0x01, 1, 2, 3, 1
        ]
    );
    #[rustfmt::skip]
    let configuration = [
        9, 2, 32, 0, 1, 1, 0, 0x80, 250,
        9, 4, 0, 0, 2, 0xff, 0, 0, 4,
        7, 5, 0x81, 2, 0x00, 0x02, 0,
        7, 5, 0x02, 2, 0x00, 0x02, 0,
    ];
    assert_eq!(d.configuration(), configuration);
    assert_eq!(d.string(0).unwrap(), [4, 3, 0x09, 0x04]);
    assert_eq!(d.string(2).unwrap(), [8, 3, b'C', 0, b'a', 0, b'm', 0]);
    assert_eq!(d.string(4).unwrap(), d.lookup(3, 4).unwrap());
    assert_eq!(d.string(5), None);
    assert_eq!(d.bos(), None);
    assert_eq!(
        d.device_qualifier().unwrap(),
        [10, 6, 0x00, 0x02, 0, 0, 0, 64, 1, 0]
    );
    assert_eq!(d.endpoints(), [0x81, 0x02]);
    assert_eq!(d.speed().usbip_speed(), 3);
}

#[test]
fn superspeed_adds_companions_and_bos() {
    let d = DeviceDescriptors::build(&spec(Speed::Super)).unwrap();
    assert_eq!(&d.device()[2..4], [0x20, 0x03]);
    assert_eq!(d.device()[7], 9);
    #[rustfmt::skip]
    let configuration = [
        9, 2, 44, 0, 1, 1, 0, 0x80, 62,
        9, 4, 0, 0, 2, 0xff, 0, 0, 4,
        7, 5, 0x81, 2, 0x00, 0x04, 0,
        6, 0x30, 15, 0, 0, 0,
        7, 5, 0x02, 2, 0x00, 0x04, 0,
        6, 0x30, 0, 0, 0, 0,
    ];
    assert_eq!(d.configuration(), configuration);
    let bos = d.bos().unwrap();
    assert_eq!(bos[..5], [5, 0x0f, 22, 0, 2]);
    assert_eq!(bos.len(), 22);
    assert_eq!(bos[12..15], [10, 0x10, 0x03]);
    assert_eq!(d.device_qualifier(), None);
    assert_eq!(d.speed().usbip_speed(), 5);
}

#[test]
fn utf16_strings_and_limits() {
    let mut s = DeviceSpec::new(Speed::High, 1, 2);
    s.product = Some("é€".into());
    let d = DeviceDescriptors::build(&s).unwrap();
    assert_eq!(d.device()[14..17], [0, 1, 0]);
    assert_eq!(d.string(1).unwrap(), [6, 3, 0xe9, 0x00, 0xac, 0x20]);

    s.product = Some("x".repeat(127));
    assert!(matches!(
        DeviceDescriptors::build(&s),
        Err(DescriptorError::StringTooLong(_))
    ));
    s.product = Some("x".repeat(126));
    assert_eq!(
        DeviceDescriptors::build(&s)
            .unwrap()
            .string(1)
            .unwrap()
            .len(),
        254
    );

    let repeated = spec(Speed::High).with_interface(InterfaceSpec {
        endpoints: vec![EndpointSpec::bulk_in(1)],
        ..InterfaceSpec::default()
    });
    assert_eq!(
        DeviceDescriptors::build(&repeated),
        Err(DescriptorError::BadEndpoint(0x81))
    );
    let zero = DeviceSpec::new(Speed::High, 1, 2).with_interface(InterfaceSpec {
        endpoints: vec![EndpointSpec::bulk_out(0)],
        ..InterfaceSpec::default()
    });
    assert_eq!(
        DeviceDescriptors::build(&zero),
        Err(DescriptorError::BadEndpoint(0))
    );
    let burst = DeviceSpec::new(Speed::Super, 1, 2).with_interface(InterfaceSpec {
        endpoints: vec![EndpointSpec::bulk_out(1).with_max_burst(16)],
        ..InterfaceSpec::default()
    });
    assert_eq!(
        DeviceDescriptors::build(&burst),
        Err(DescriptorError::BadMaxBurst(16))
    );
}
