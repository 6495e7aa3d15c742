//! Each of `drive.manuals` is one kind: a text file cited by line (`file:`) or a document with
//! no text at hand cited by page (`id:` with `document:` and/or `url:`); names are unique.

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::source::Path;

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let list = Path::root().key("drive").key("manuals");
    for (i, m) in drive.meta.manuals.iter().enumerate() {
        let path = list.index(i);
        let mut error = |key: Option<&str>, message: String| {
            let at = key.map_or_else(|| path.clone(), |k| path.key(k));
            out.push(drive.error(&at, None, message));
        };
        match (&m.file, &m.id) {
            (Some(_), Some(_)) => error(
                Some("id"),
                "a manual has a `file` (an OCR text, cited `file:line`) or an `id` (a document \
                 with no text at hand, cited `<id>:p<page>`), not both"
                    .to_owned(),
            ),
            (None, None) => error(
                None,
                "a manual needs `file: <text file in the manuals folder>` (cited `file:line`), or \
                 `id: <name>` with `document:` and/or `url:` (cited `<id>:p<page>`)"
                    .to_owned(),
            ),
            (None, Some(id)) => {
                if id.is_empty() || id.contains(|c: char| c == ':' || c.is_whitespace()) {
                    error(
                        Some("id"),
                        format!(
                            "manual id `{id}` must be non-empty, without `:` or spaces (citations read `<id>:p<page>`)"
                        ),
                    );
                }
                if m.document.is_none() && m.url.is_none() {
                    error(
                        None,
                        format!(
                            "manual `{id}` has no text at hand, so a reader needs its `document` (number and revision as printed) or its `url`"
                        ),
                    );
                }
            }
            (Some(_), None) => {}
        }
        if let Some(url) = &m.url
            && !(url.starts_with("https://") || url.starts_with("http://"))
        {
            error(
                Some("url"),
                format!("manual url `{url}` is not an http(s) address"),
            );
        }
        let name = m.name();
        if !name.is_empty()
            && drive.meta.manuals[..i]
                .iter()
                .any(|other| other.name() == name)
        {
            error(None, format!("manual `{name}` is listed twice"));
        }
    }
}
