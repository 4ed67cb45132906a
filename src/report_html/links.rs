//! Links from a report page to the files it lists, relative to the page's
//! folder: the page and its outputs move together (copied to a review
//! folder, served from a share) and the links still open the files.

use std::path::{Component, Path, PathBuf};

/// `path` made absolute (against the current folder) with `.` and `..`
/// resolved by name, as a list of its parts.
fn parts(path: &Path) -> Option<Vec<String>> {
    let absolute: PathBuf = std::path::absolute(path).ok()?;
    let mut parts: Vec<String> = Vec::new();
    for component in absolute.components() {
        match component {
            Component::Normal(name) => parts.push(name.to_string_lossy().into_owned()),
            Component::ParentDir => {
                parts.pop();
            }
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    Some(parts)
}

/// Characters a URL path cannot hold as they are.
fn encode(part: &str) -> String {
    let mut out = String::with_capacity(part.len());
    for c in part.chars() {
        match c {
            '%' => out.push_str("%25"),
            ' ' => out.push_str("%20"),
            '#' => out.push_str("%23"),
            '?' => out.push_str("%3F"),
            c => out.push(c),
        }
    }
    out
}

/// The URL of `target` relative to the folder `from` (`../b/x.usda`);
/// `None` when either cannot be made absolute.
pub fn relative_href(from: &Path, target: &Path) -> Option<String> {
    let from = parts(from)?;
    let to = parts(target)?;
    let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
    let mut link: Vec<String> = vec!["..".to_string(); from.len() - common];
    link.extend(to[common..].iter().map(|p| encode(p)));
    Some(link.join("/"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_go_up_and_down_from_the_page() {
        let href = |a: &str, b: &str| relative_href(Path::new(a), Path::new(b)).unwrap();
        assert_eq!(href("/r/out", "/r/out/a.usda"), "a.usda");
        assert_eq!(
            href("/r/out", "/r/shots/b c/x#1.abc"),
            "../shots/b%20c/x%231.abc"
        );
        assert_eq!(href("/r/out/./x/..", "/r/out/y/../a.glb"), "a.glb");
    }
}
