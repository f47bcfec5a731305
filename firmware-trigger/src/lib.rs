//! Trigger firmware schedule core (to be built out by the firmware issue).
#![no_std]
