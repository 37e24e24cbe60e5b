//! (c) The weights file (JSON). A file that is accepted holds a usable net: it writes back
//! to JSON that reads as the same file, and a raw-input net evaluates to finite outputs
//! anywhere in the range it was trained on.

#![no_main]

use libfuzzer_sys::fuzz_target;
use neurarm_nn::{InputEncoding, WeightsFile};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(file) = WeightsFile::from_json(text, "fuzz.json") else { return };
    let net = file.network().expect("an accepted file has a net");
    let again = WeightsFile::from_json(&file.to_json(), "again.json").expect("an accepted file reads back");
    assert_eq!(again, file, "JSON round trip");
    let n = file.inputs.len();
    let (mut features, mut hidden, mut out) = (vec![0.0; net.features()], vec![0.0; net.hidden()], vec![0.0; net.outputs()]);
    if file.encoding == InputEncoding::Raw {
        let s = &file.input_scaling;
        for x in [s.min.clone(), s.max.clone(), (0..n).map(|i| 0.5 * s.min[i] + 0.5 * s.max[i]).collect()] {
            net.evaluate_into(&x, &mut features, &mut hidden, &mut out);
            assert!(out.iter().all(|v| v.is_finite()), "net({x:?}) = {out:?}");
        }
    } else {
        // Any angles: no panic (finiteness depends on the scaling of the encoded features).
        net.evaluate_into(&vec![0.5; n], &mut features, &mut hidden, &mut out);
    }
});
