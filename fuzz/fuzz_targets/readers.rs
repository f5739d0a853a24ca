//! Any bytes, as a certificate and as a state file: the readers must return, never panic.
#![no_main]

use lagra_checker::certificate::Certificate;
use lagra_checker::states::States;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = Certificate::read(text);
    }
    let _ = States::read(data.to_vec());
});
