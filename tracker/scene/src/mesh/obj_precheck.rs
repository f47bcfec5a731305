//! Checks of OBJ and MTL text that `tobj` 4 would panic on instead of reporting: each returns the reason to refuse
//! the file, naming the line, or `None` when `tobj` can be trusted with it.

/// The first colour line (`Ka`, `Kd`, `Ks`, `Ke`) of an MTL file with fewer than three numbers.
pub(super) fn short_colour_line(mtl: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(mtl);
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        let key = words.next()?;
        let found = words.count();
        (matches!(key, "Ka" | "Kd" | "Ks" | "Ke") && found < 3).then(|| {
            format!(
                "line {}: `{key}` needs three numbers (red, green, blue), found {found}",
                i + 1
            )
        })
    })
}

/// What a face vertex's index (`v/vt/vn`, in that order) refers to.
const ELEMENTS: [(&str, &str); 3] = [
    ("v", "vertex position"),
    ("vt", "texture coordinate"),
    ("vn", "normal"),
];

/// The first face (`f`) vertex of an OBJ file whose position, texture coordinate or normal index lies outside
/// the elements the file defines.
///
/// Indices count from 1; a negative one counts back from the last element defined above the face. A texture
/// coordinate or normal index is only checked when the file defines some (without any, `tobj` ignores them).
pub(super) fn face_index_out_of_range(obj: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(obj);
    let mut totals = [0i128; 3];
    for line in text.lines() {
        if let Some(k) = element_kind(line) {
            totals[k] += 1;
        }
    }
    let mut defined = [0i128; 3];
    for (i, line) in text.lines().enumerate() {
        if let Some(k) = element_kind(line) {
            defined[k] += 1;
            continue;
        }
        let mut words = line.split_whitespace();
        if words.next() != Some("f") {
            continue;
        }
        for vertex in words {
            for (k, index) in vertex.split('/').enumerate().take(3) {
                // Not a number: `tobj` reports the face itself.
                let Ok(index) = index.parse::<i128>() else {
                    continue;
                };
                let resolved = if index < 0 {
                    defined[k] + index
                } else {
                    index - 1
                };
                let checked = k == 0 || totals[k] > 0;
                if checked && !(0..totals[k]).contains(&resolved) {
                    let (key, element) = ELEMENTS[k];
                    return Some(format!(
                        "line {}: face vertex `{vertex}` refers to {element} {index}, but the file defines {} \
                         (`{key}` lines; indices count from 1, negative ones back from the last defined above)",
                        i + 1,
                        totals[k]
                    ));
                }
            }
        }
    }
    None
}

/// Which element (0 position, 1 texture coordinate, 2 normal) an OBJ line defines, if any.
fn element_kind(line: &str) -> Option<usize> {
    match line.split_whitespace().next()? {
        "v" => Some(0),
        "vt" => Some(1),
        "vn" => Some(2),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_within_the_defined_elements_pass() {
        let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/-1/1 -1/1/-1\n";
        assert_eq!(face_index_out_of_range(obj), None);
    }

    #[test]
    fn a_relative_texture_coordinate_before_the_first_is_refused_by_line() {
        let obj = b"v 0 0 0\nvt 0 0\nv 0 0 0\nf 1/-99999999999 1 1\n";
        let reason = face_index_out_of_range(obj).expect("refused");
        assert!(reason.starts_with("line 4:"), "{reason}");
        assert!(
            reason.contains("texture coordinate -99999999999"),
            "{reason}"
        );
    }

    #[test]
    fn positions_past_the_last_and_index_zero_are_refused() {
        assert!(face_index_out_of_range(b"v 0 0 0\nf 1 1 2\n").is_some());
        assert!(face_index_out_of_range(b"v 0 0 0\nf 1 0 1\n").is_some());
        assert!(
            face_index_out_of_range(b"v 0 0 0\nvn 0 0 1\nf 1//9223372036854775807 1 1\n").is_some()
        );
    }

    #[test]
    fn normal_indices_without_normals_are_left_to_tobj() {
        assert_eq!(
            face_index_out_of_range(b"v 0 0 0\nf 1//5 1//5 1//5\n"),
            None
        );
    }

    #[test]
    fn a_colour_line_with_two_numbers_is_refused() {
        assert!(short_colour_line(b"newmtl a\nKd 0 0\n").is_some());
        assert_eq!(short_colour_line(b"newmtl a\nKd 0 0 0\n"), None);
    }
}
