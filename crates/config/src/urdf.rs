//! What the loader checks of a URDF before the model reads it: a bounded
//! size, and a count of links and joints an arm can have, so that a
//! 100 000-link file is refused at once, naming the URDF and the limit,
//! instead of a service failing on it later.

use std::io::Read;
use std::path::Path;

/// The most `<link>` elements a robot description may have (the deployed
/// arms have 9-13; a mobile manipulator with two arms and a hand some 60).
pub const MAX_URDF_LINKS: usize = 256;
/// The most `<joint>` elements.
pub const MAX_URDF_JOINTS: usize = 256;

/// The text of the open URDF `file`, at most [`phri_model::MAX_URDF_BYTES`].
pub(crate) fn read_bounded(file: std::fs::File, path: &Path) -> std::io::Result<String> {
    let mut bytes = Vec::new();
    file.take(phri_model::MAX_URDF_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > phri_model::MAX_URDF_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "larger than {} bytes: not a robot description ({})",
                phri_model::MAX_URDF_BYTES,
                path.display()
            ),
        ));
    }
    String::from_utf8(bytes)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// Elements `<name` (followed by white space, `>` or `/`) outside comments.
fn count_elements(text: &str, name: &str) -> usize {
    let mut n = 0;
    let mut rest = text;
    while let Some(i) = rest.find('<') {
        rest = &rest[i..];
        if let Some(after) = rest.strip_prefix("<!--") {
            rest = after.find("-->").map_or("", |j| &after[j + 3..]);
            continue;
        }
        let tail = &rest[1..];
        if let Some(after) = tail.strip_prefix(name) {
            if after.starts_with(|c: char| c.is_whitespace() || c == '>' || c == '/') {
                n += 1;
            }
        }
        rest = tail;
    }
    n
}

/// The URDF text has at most [`MAX_URDF_LINKS`] links and
/// [`MAX_URDF_JOINTS`] joints; the error says how many and the limit.
pub fn check_size(text: &str) -> Result<(), String> {
    let links = count_elements(text, "link");
    let joints = count_elements(text, "joint");
    if links > MAX_URDF_LINKS || joints > MAX_URDF_JOINTS {
        return Err(format!(
            "{links} links and {joints} joints, at most {MAX_URDF_LINKS} links and \
             {MAX_URDF_JOINTS} joints: not a robot arm's description"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_and_joints_are_counted_outside_comments() {
        let text = r#"<robot name="r"><!-- <link name="c"/> --><link name="a"/>
            <link name="b"><visual/></link><joint name="j" type="fixed"><parent link="a"/></joint>
            <linkage/></robot>"#;
        assert_eq!(count_elements(text, "link"), 2);
        assert_eq!(count_elements(text, "joint"), 1);
        check_size(text).unwrap();
        let many: String = (0..=MAX_URDF_LINKS)
            .map(|i| format!("<link name=\"l{i}\"/>"))
            .collect();
        let e = check_size(&many).unwrap_err();
        assert!(
            e.starts_with("257 links and 0 joints, at most 256 links"),
            "{e}"
        );
        // the deployed arms pass
        for arm in [
            "kuka_lwr4.urdf",
            "fr3/fr3.urdf",
            "panda/panda.urdf",
            "panda/panda_collision.urdf",
        ] {
            let p = Path::new(crate::DEFAULT_DEPLOY_DIR)
                .join("robots")
                .join(arm);
            check_size(&std::fs::read_to_string(&p).unwrap()).unwrap();
        }
    }
}
