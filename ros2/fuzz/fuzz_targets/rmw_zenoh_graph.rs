#![no_main]
//! Fuzz rmw_zenoh's sample attachment parser and the ROS 2 name checks: no panic on any input; an attachment that
//! parses gives back exactly the input bytes; a name path passes the check exactly when each of its components is
//! a valid name token, and a mangled name has no `/` left.

use libfuzzer_sys::fuzz_target;
use ros2::{Attachment, check_name_path, check_name_token, mangle_name};

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = Attachment::from_bytes(data) {
        assert_eq!(a.to_bytes().as_slice(), data);
        assert_eq!(Attachment::from_bytes(&a.to_bytes()), Ok(a));
    }
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let trimmed = text.trim_matches('/');
    let tokens_ok = trimmed.is_empty() || trimmed.split('/').all(|t| check_name_token(t).is_ok());
    assert_eq!(check_name_path(text).is_ok(), tokens_ok, "{text:?}");
    if check_name_token(text).is_ok() {
        assert!(check_name_path(text).is_ok(), "{text:?}");
        assert!(text.is_ascii() && !text.is_empty());
    }
    assert!(!mangle_name(text).contains('/'));
});
