//! "Did you mean": the nearest known spelling of a misspelt keyword, parameter or name.

/// The edit distance between `a` and `b` (case-insensitive, ASCII) with a swap of two adjacent
/// letters counted as one edit (the optimal string alignment distance): `GIRD` is one edit from
/// `GRID`, as a typist's slip is.
fn distance(a: &str, b: &str) -> usize {
    let a: Vec<u8> = a.bytes().map(|c| c.to_ascii_uppercase()).collect();
    let b: Vec<u8> = b.bytes().map(|c| c.to_ascii_uppercase()).collect();
    // rows i - 2, i - 1 and i of the table
    let mut before: Vec<usize> = Vec::new();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
            if i > 0 && j > 0 && *ca == b[j - 1] && a[i - 1] == *cb {
                cur[j + 1] = cur[j + 1].min(before[j - 1] + 1);
            }
        }
        before = std::mem::replace(&mut prev, cur);
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
        // a swap of two adjacent letters is one edit (Levenshtein counts two)
        assert_eq!(distance("GIRD", "GRID"), 1);
        assert_eq!(distance("ELASITC", "ELASTIC"), 1);
        assert_eq!(distance("CHEXAA", "CHEXA"), 1);
        // no swap shortcut across a third letter: ab-c-d against cb-a-d is two substitutions
        assert_eq!(distance("abcd", "cbad"), 2);
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
