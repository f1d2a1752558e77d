//! Bake part files, as `kelvin bake --merge` reads them from another machine: bytes ->
//! `BakePart::from_bytes`. An error is fine; a panic, or an accepted part that does not write back
//! to the same bytes, is a crash.
#![no_main]

use kelvin::bake::BakePart;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(part) = BakePart::from_bytes(data, "fuzz") else { return };
    let again = part.to_bytes();
    let back = BakePart::from_bytes(&again, "again").expect("a part's own bytes read back");
    assert_eq!(back.to_bytes(), again, "a part's bytes are stable");
    let p = part.part();
    assert!(p.index < p.count, "part {} of {}", p.index, p.count);
});
