//! "Did you mean": the nearest known spelling of a misspelt keyword, parameter or name.

/// The Levenshtein distance between `a` and `b` (case-insensitive, ASCII).
fn distance(a: &str, b: &str) -> usize {
    let a: Vec<u8> = a.bytes().map(|c| c.to_ascii_uppercase()).collect();
    let b: Vec<u8> = b.bytes().map(|c| c.to_ascii_uppercase()).collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The known spelling nearest `word`, if it is close enough to be a typo: at most a third of the
/// longer word's letters differ (at least one edit allowed).
pub(crate) fn nearest<'a>(word: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    known
        .into_iter()
        .map(|k| (distance(word, k), k))
        .filter(|(d, k)| *d > 0 && *d <= (word.len().max(k.len()) / 3).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// `" (did you mean X?)"` with `prefix` before `X`, or nothing.
pub(crate) fn suggestion<'a>(
    word: &str,
    known: impl IntoIterator<Item = &'a str>,
    prefix: &str,
) -> String {
    nearest(word, known)
        .map(|k| format!(" (did you mean {prefix}{k}?)"))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_by_hand() {
        // kitten -> sitten -> sittin -> sitting
        assert_eq!(distance("kitten", "sitting"), 3);
        assert_eq!(distance("BOUNDRY", "boundary"), 1);
        assert_eq!(distance("GENERTE", "GENERATE"), 1);
        assert_eq!(distance("", "abc"), 3);
    }

    #[test]
    fn nearest_only_when_close() {
        let known = ["BOUNDARY", "ELEMENT", "ELSET", "NSET"];
        assert_eq!(nearest("BOUNDRY", known), Some("BOUNDARY"));
        assert_eq!(nearest("ELEMNT", known), Some("ELEMENT"));
        assert_eq!(nearest("FOO", known), None);
        assert_eq!(nearest("NSET", known), None, "an exact match is not a typo");
    }
}
