//! Just enough JSON for the `source_names` parameter: an array of strings.

/// Parse `["a", "b\"c", ...]`; `None` unless the whole text is such an array.
pub(crate) fn string_array(s: &str) -> Option<Vec<String>> {
    let mut chars = s.trim().chars().peekable();
    let mut out = Vec::new();
    if chars.next()? != '[' {
        return None;
    }
    let skip_ws = |c: &mut std::iter::Peekable<std::str::Chars>| {
        while c.peek().is_some_and(|x| x.is_whitespace()) {
            c.next();
        }
    };
    skip_ws(&mut chars);
    if chars.peek() == Some(&']') {
        chars.next();
        return chars.next().is_none().then_some(out);
    }
    loop {
        skip_ws(&mut chars);
        if chars.next()? != '"' {
            return None;
        }
        let mut v = String::new();
        loop {
            match chars.next()? {
                '"' => break,
                '\\' => match chars.next()? {
                    '"' => v.push('"'),
                    '\\' => v.push('\\'),
                    '/' => v.push('/'),
                    'b' => v.push('\u{8}'),
                    'f' => v.push('\u{c}'),
                    'n' => v.push('\n'),
                    'r' => v.push('\r'),
                    't' => v.push('\t'),
                    'u' => {
                        let mut hex = || -> Option<u32> {
                            (0..4).try_fold(0u32, |a, _| Some(a * 16 + chars.next()?.to_digit(16)?))
                        };
                        let hi = hex()?;
                        let c = if (0xD800..0xDC00).contains(&hi) {
                            if chars.next()? != '\\' || chars.next()? != 'u' {
                                return None;
                            }
                            let lo = (0..4).try_fold(0u32, |a, _| {
                                Some(a * 16 + chars.next()?.to_digit(16)?)
                            })?;
                            if !(0xDC00..0xE000).contains(&lo) {
                                return None;
                            }
                            0x10000 + ((hi - 0xD800) << 10) + (lo - 0xDC00)
                        } else {
                            hi
                        };
                        v.push(char::from_u32(c)?);
                    }
                    _ => return None,
                },
                c if (c as u32) < 0x20 => return None,
                c => v.push(c),
            }
        }
        out.push(v);
        skip_ws(&mut chars);
        match chars.next()? {
            ',' => continue,
            ']' => break,
            _ => return None,
        }
    }
    skip_ws(&mut chars);
    chars.next().is_none().then_some(out)
}

#[cfg(test)]
mod tests {
    use super::string_array;

    #[test]
    fn arrays_of_strings() {
        assert_eq!(string_array("[]"), Some(vec![]));
        assert_eq!(
            string_array(r#" ["a", "b\"c\\", "\u00e9\ud83d\ude00"] "#),
            Some(vec!["a".into(), "b\"c\\".into(), "é😀".into()])
        );
        for bad in ["", "[", "[1]", r#"["a",]"#, r#"["a"] x"#, r#"["\x"]"#, "{}"] {
            assert_eq!(string_array(bad), None, "{bad}");
        }
    }
}
