//! Words that name one of a few choices (`--inside above`, `lattice="bcc"`), parsed once for
//! every front end: the CLI, the Python package and anyone calling `str::parse`. A word is
//! matched without regard to case; an unknown one is refused naming the setting and the words
//! it takes.

/// A word that names none of a setting's choices.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{setting} '{given}': expected {}", expected(valid))]
pub struct UnknownChoice {
    /// The setting (`inside`, `lattice`, ...).
    pub setting: &'static str,
    /// The word given.
    pub given: String,
    /// The words it takes.
    pub valid: Vec<&'static str>,
}

/// `'a'`, `'a' or 'b'`, `'a', 'b' or 'c'`.
fn expected(valid: &[&str]) -> String {
    let quoted: Vec<String> = valid.iter().map(|v| format!("'{v}'")).collect();
    match quoted.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => "nothing".into(),
    }
}

/// The choice `text` names in `table` (word, value), any case, or the error naming `setting`.
pub fn parse_choice<T: Copy>(setting: &'static str, text: &str, table: &[(&'static str, T)]) -> Result<T, UnknownChoice> {
    let word = text.trim();
    table.iter().find(|(name, _)| name.eq_ignore_ascii_case(word)).map(|&(_, value)| value).ok_or_else(|| UnknownChoice {
        setting,
        given: text.to_owned(),
        valid: table.iter().map(|(name, _)| *name).collect(),
    })
}

/// The word that names `value` in `table` (the first, should two name it).
pub fn choice_name<T: PartialEq>(value: &T, table: &[(&'static str, T)]) -> &'static str {
    table.iter().find(|(_, v)| v == value).map_or("?", |(name, _)| name)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: [(&str, u8); 3] = [("one", 1), ("two", 2), ("three", 3)];

    #[test]
    fn words_parse_in_any_case_and_unknown_ones_name_the_setting_and_the_choices() {
        assert_eq!(parse_choice("count", "Two", &TABLE), Ok(2));
        assert_eq!(parse_choice("count", " three ", &TABLE), Ok(3));
        let err = parse_choice("count", "four", &TABLE).unwrap_err();
        assert_eq!(err.to_string(), "count 'four': expected 'one', 'two' or 'three'");
        assert_eq!(parse_choice("count", "x", &TABLE[..1]).unwrap_err().to_string(), "count 'x': expected 'one'");
        assert_eq!(choice_name(&3, &TABLE), "three");
    }
}
