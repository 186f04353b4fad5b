//! The raw IGES file: 80-column cards in five sections, the Global section with the delimiters
//! it declares, directory entries, and each entity's parameter record split into tokens that
//! remember their file line (IGES 5.3 §2; the fields are listed in the module docs above).

use super::IgesError;

/// One parameter token: its text as written (trimmed; a Hollerith string's characters) and the
/// file line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// The text; for a Hollerith string, its characters after `nH`.
    pub text: String,
    /// `true` for a Hollerith string.
    pub hollerith: bool,
    /// 1-based file line.
    pub line: usize,
}

/// The Global section's parameters a reader uses.
#[derive(Clone, Debug, PartialEq)]
pub struct Global {
    /// G1.
    pub parameter_delimiter: char,
    /// G2.
    pub record_delimiter: char,
    /// G3: the sender's product identification.
    pub product: String,
    /// G5: the native system.
    pub system: String,
    /// G13: model space units per real-world unit.
    pub model_scale: f64,
    /// G14: 1 inch, 2 mm, 3 named by G15, 4 foot, 5 mile, 6 m, 7 km, 8 mil, 9 µm, 10 cm, 11 µin.
    pub units_flag: i64,
    /// G15.
    pub units_name: String,
    /// G19: the smallest distance the sender tells apart, in model units.
    pub min_resolution: f64,
    /// G23: 11 for IGES 5.3.
    pub version: i64,
}

impl Global {
    /// Millimetres per model unit (G13, G14, G15).
    pub fn millimetres_per_unit(&self) -> Result<f64, String> {
        let unit = match self.units_flag {
            1 => 25.4,
            2 => 1.0,
            3 => match self.units_name.trim().to_ascii_uppercase().as_str() {
                "MM" => 1.0,
                "IN" | "INCH" => 25.4,
                "FT" => 304.8,
                "M" => 1000.0,
                "CM" => 10.0,
                "UM" => 1e-3,
                other => return Err(format!("units '{other}' (G15) are not known")),
            },
            4 => 304.8,
            5 => 1_609_344.0,
            6 => 1000.0,
            7 => 1e6,
            8 => 0.0254,
            9 => 1e-3,
            10 => 10.0,
            11 => 2.54e-5,
            flag => return Err(format!("units flag {flag} (G14) is not 1 to 11")),
        };
        if !(self.model_scale.is_finite() && self.model_scale > 0.0) {
            return Err(format!(
                "model scale {} (G13) must be positive",
                self.model_scale
            ));
        }
        Ok(unit / self.model_scale)
    }
}

/// A directory entry's status number (field 9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// 0 visible, 1 blanked.
    pub blank: u8,
    /// 0 independent, 1 physically, 2 logically, 3 both dependent.
    pub subordinate: u8,
    /// 0 geometry, …, 5 2D parametric, 6 construction.
    pub use_flag: u8,
    /// 0 top-down, 1 defer, 2 hierarchy property.
    pub hierarchy: u8,
}

/// One entity: its directory entry and its parameter tokens.
#[derive(Clone, Debug, PartialEq)]
pub struct RawEntity {
    /// Its DE pointer: the sequence number of its first directory card (odd).
    pub de: usize,
    /// The file line of that card.
    pub line: usize,
    /// Field 1.
    pub entity_type: i64,
    /// Field 15.
    pub form: i64,
    /// Field 7: the DE of a transformation matrix (124), or 0.
    pub transform: usize,
    /// Field 9.
    pub status: Status,
    /// Field 13: a colour number, or minus the DE of a colour entity (314).
    pub colour: i64,
    /// The parameter record, the entity type first: index `i` is the spec's parameter `i`.
    pub parameters: Vec<Token>,
}

/// The file read into entities.
#[derive(Clone, Debug, PartialEq)]
pub struct RawFile {
    /// The Global section.
    pub global: Global,
    /// In directory order.
    pub entities: Vec<RawEntity>,
}

impl RawFile {
    /// The entity with DE pointer `de`.
    pub fn entity(&self, de: usize) -> Option<&RawEntity> {
        if de == 0 || de.is_multiple_of(2) {
            return None;
        }
        self.entities.get((de - 1) / 2).filter(|e| e.de == de)
    }
}

/// A card's section letter, sequence number and its 1-based line.
struct Card<'a> {
    text: &'a str,
    line: usize,
}

impl Card<'_> {
    /// Columns `from..=to` (1-based), clipped to the card.
    fn columns(&self, from: usize, to: usize) -> &str {
        let end = to.min(self.text.len());
        if from > end {
            ""
        } else {
            &self.text[from - 1..end]
        }
    }
}

/// Splits the text into its sections' cards, checking columns 73–80.
fn sections(text: &str) -> Result<[Vec<Card<'_>>; 5], IgesError> {
    let mut out: [Vec<Card<'_>>; 5] = Default::default();
    let mut last = 0usize;
    for (k, raw) in text.split('\n').enumerate() {
        let line = k + 1;
        let card = raw.trim_end_matches('\r');
        if card.trim().is_empty() {
            continue;
        }
        if !card.is_ascii() {
            return Err(IgesError::at(line, "a card with characters outside ASCII"));
        }
        if card.len() < 73 {
            return Err(IgesError::at(
                line,
                format!(
                    "a card of {} columns: the section letter belongs in column 73",
                    card.len()
                ),
            ));
        }
        let section = match &card[72..73] {
            "S" => 0,
            "G" => 1,
            "D" => 2,
            "P" => 3,
            "T" => 4,
            "C" | "B" => {
                return Err(IgesError::at(
                    line,
                    "compressed or binary IGES: only the fixed ASCII form is read",
                ));
            }
            other => {
                return Err(IgesError::at(
                    line,
                    format!("section letter '{other}' in column 73 (S, G, D, P or T expected)"),
                ));
            }
        };
        if section < last {
            return Err(IgesError::at(
                line,
                "a section out of order (S, G, D, P, T)",
            ));
        }
        last = section;
        out[section].push(Card { text: card, line });
    }
    if out[2].is_empty() || out[3].is_empty() {
        return Err(IgesError::at(
            1,
            "no directory (D) or parameter (P) section: not an IGES file",
        ));
    }
    Ok(out)
}

/// Splits `text` (with each character's line in `lines`) into tokens up to the record
/// delimiter; returns the tokens and whether the record delimiter was met.
fn tokenize(
    text: &[u8],
    lines: &[usize],
    parameter: u8,
    record: u8,
) -> Result<(Vec<Token>, bool), IgesError> {
    let mut tokens = Vec::new();
    let mut i = 0;
    let line_at = |i: usize| lines.get(i).or(lines.last()).copied().unwrap_or(0);
    while i <= text.len() {
        while i < text.len() && text[i] == b' ' {
            i += 1;
        }
        let start = i;
        let mut digits = i;
        while digits < text.len() && text[digits].is_ascii_digit() {
            digits += 1;
        }
        let (value, hollerith, mut j) = if digits > i && digits < text.len() && text[digits] == b'H'
        {
            let count: usize = std::str::from_utf8(&text[i..digits])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| IgesError::at(line_at(i), "a Hollerith count too large"))?;
            let from = digits + 1;
            let to = from
                .checked_add(count)
                .filter(|&to| to <= text.len())
                .ok_or_else(|| {
                    IgesError::at(
                        line_at(i),
                        format!("a Hollerith string of {count} characters runs past the record"),
                    )
                })?;
            (
                String::from_utf8_lossy(&text[from..to]).into_owned(),
                true,
                to,
            )
        } else {
            let mut j = i;
            while j < text.len() && text[j] != parameter && text[j] != record {
                j += 1;
            }
            (
                String::from_utf8_lossy(&text[i..j]).trim().to_string(),
                false,
                j,
            )
        };
        while j < text.len() && text[j] == b' ' {
            j += 1;
        }
        if j >= text.len() {
            if !value.is_empty() || hollerith {
                tokens.push(Token {
                    text: value,
                    hollerith,
                    line: line_at(start),
                });
            }
            return Ok((tokens, false));
        }
        let delimiter = text[j];
        if delimiter != parameter && delimiter != record {
            return Err(IgesError::at(
                line_at(j),
                format!(
                    "'{}' after a Hollerith string where a delimiter belongs",
                    delimiter as char
                ),
            ));
        }
        tokens.push(Token {
            text: value,
            hollerith,
            line: line_at(start),
        });
        if delimiter == record {
            return Ok((tokens, true));
        }
        i = j + 1;
    }
    Ok((tokens, false))
}

/// The data columns of `cards` joined, with each byte's line.
fn joined(cards: &[Card<'_>], from: usize, to: usize) -> (Vec<u8>, Vec<usize>) {
    let mut text = Vec::new();
    let mut lines = Vec::new();
    for card in cards {
        let data = card.columns(from, to);
        text.extend_from_slice(data.as_bytes());
        // Short data fields are padded: a token never runs into the next card's.
        text.extend(std::iter::repeat_n(
            b' ',
            (to - from + 1).saturating_sub(data.len()),
        ));
        lines.extend(std::iter::repeat_n(card.line, to - from + 1));
    }
    (text, lines)
}

/// The Global section: its two delimiters first (each `1Hc`, or empty for `,` and `;`), then
/// the rest with them.
fn global(cards: &[Card<'_>]) -> Result<Global, IgesError> {
    let (text, lines) = joined(cards, 1, 72);
    let first_line = cards.first().map_or(1, |c| c.line);
    let mut i = 0;
    let declared = |default: u8, i: &mut usize, parameter: u8| -> Result<u8, IgesError> {
        while *i < text.len() && text[*i] == b' ' {
            *i += 1;
        }
        if text.get(*i) == Some(&parameter) || (parameter == 0 && text.get(*i) == Some(&b',')) {
            return Ok(default);
        }
        if text.get(*i..*i + 2) == Some(b"1H") && *i + 2 < text.len() {
            let c = text[*i + 2];
            *i += 3;
            while *i < text.len() && text[*i] == b' ' {
                *i += 1;
            }
            return Ok(c);
        }
        Err(IgesError::at(
            first_line,
            "the Global section must open with its delimiters (1H, and 1H; or empty fields)",
        ))
    };
    let parameter = declared(b',', &mut i, 0)?;
    if text.get(i) != Some(&parameter) {
        return Err(IgesError::at(
            first_line,
            "the Global section's parameter delimiter is not followed by itself",
        ));
    }
    i += 1;
    let record = declared(b';', &mut i, parameter)?;
    if parameter == record || parameter == b' ' || record == b' ' {
        return Err(IgesError::at(
            first_line,
            "the Global section declares equal or blank delimiters",
        ));
    }
    // The rest: G3 onwards (an empty G2 leaves its delimiter at i).
    if text.get(i) == Some(&parameter) {
        i += 1;
    }
    let (tokens, _) = tokenize(&text[i..], &lines[i..], parameter, record)?;
    // tokens[0] is G3.
    let field = |g: usize| tokens.get(g - 3);
    let string = |g: usize| field(g).map_or(String::new(), |t| t.text.clone());
    let number = |g: usize, default: f64| -> Result<f64, IgesError> {
        match field(g) {
            Some(t) if !t.text.is_empty() => parse_real(&t.text).ok_or_else(|| {
                IgesError::at(
                    t.line,
                    format!("Global parameter {g} '{}' is not a number", t.text),
                )
            }),
            _ => Ok(default),
        }
    };
    Ok(Global {
        parameter_delimiter: parameter as char,
        record_delimiter: record as char,
        product: string(3),
        system: string(5),
        model_scale: number(13, 1.0)?,
        units_flag: number(14, 1.0)? as i64,
        units_name: string(15),
        min_resolution: number(19, 0.0)?,
        version: number(23, 0.0)? as i64,
    })
}

/// A real as IGES writes it: `1.`, `-7.35E-015`, `2.5D3`.
pub fn parse_real(text: &str) -> Option<f64> {
    let t = text.trim().replace(['D', 'd'], "E");
    let v: f64 = t.parse().ok()?;
    v.is_finite().then_some(v)
}

/// An 8-column directory field as an integer (blank: 0).
fn field(card: &Card<'_>, index: usize, what: &str) -> Result<i64, IgesError> {
    let text = card.columns(8 * index - 7, 8 * index).trim();
    if text.is_empty() {
        return Ok(0);
    }
    text.parse().map_err(|_| {
        IgesError::at(
            card.line,
            format!("directory field {index} ({what}) '{text}' is not an integer"),
        )
    })
}

/// Reads an IGES file's text into its Global parameters and entities.
pub fn read_raw(text: &str) -> Result<RawFile, IgesError> {
    let [_, g, d, p, _] = sections(text)?;
    let global = global(&g)?;
    if d.len() % 2 != 0 {
        return Err(IgesError::at(
            d.last().map_or(1, |c| c.line),
            "the directory section has an odd number of cards (two per entity)",
        ));
    }
    let parameter = global.parameter_delimiter as u8;
    let record = global.record_delimiter as u8;
    // P cards by sequence number.
    let p_first_seq = 1;
    let mut entities = Vec::with_capacity(d.len() / 2);
    for (k, pair) in d.chunks(2).enumerate() {
        let (a, b) = (&pair[0], &pair[1]);
        let de = 2 * k + 1;
        let entity_type = field(a, 1, "entity type")?;
        let pointer = field(a, 2, "parameter data pointer")?;
        let transform = field(a, 7, "transformation matrix")?;
        let status_text = a.columns(65, 72).trim();
        let status_text = format!("{status_text:0>8}");
        let digit = |k: usize| {
            status_text[k..k + 2].parse::<u8>().map_err(|_| {
                IgesError::at(
                    a.line,
                    format!("status number '{status_text}' is not 8 digits"),
                )
            })
        };
        let status = Status {
            blank: digit(0)?,
            subordinate: digit(2)?,
            use_flag: digit(4)?,
            hierarchy: digit(6)?,
        };
        if field(b, 1, "entity type")? != entity_type {
            return Err(IgesError::at(
                b.line,
                format!("the second directory card of DE {de} names another entity type"),
            ));
        }
        let colour = field(b, 3, "colour")?;
        let count = field(b, 4, "parameter line count")?;
        let form = field(b, 5, "form number")?;
        let lines_range = usize::try_from(pointer)
            .ok()
            .filter(|&p| p >= p_first_seq)
            .and_then(|p| Some(p - 1..(p - 1).checked_add(usize::try_from(count).ok()?)?))
            .filter(|r| r.end <= p.len() && !r.is_empty())
            .ok_or_else(|| {
                IgesError::at(
                    a.line,
                    format!(
                        "entity {entity_type} at DE {de}: parameter lines {pointer}+{count} are \
                         not in the parameter section's {} lines",
                        p.len()
                    ),
                )
            })?;
        let cards = &p[lines_range];
        for card in cards {
            let owner = card.columns(66, 72).trim();
            if owner.parse::<usize>().ok() != Some(de) {
                return Err(IgesError::at(
                    card.line,
                    format!(
                        "this parameter line belongs to DE '{owner}', but DE {de} (entity \
                         {entity_type}) points to it"
                    ),
                ));
            }
        }
        let (text, lines) = joined(cards, 1, 64);
        let (parameters, closed) = tokenize(&text, &lines, parameter, record)?;
        if !closed {
            return Err(IgesError::at(
                cards.last().map_or(a.line, |c| c.line),
                format!(
                    "entity {entity_type} at DE {de}: its parameters do not end with the record \
                     delimiter '{}'",
                    record as char
                ),
            ));
        }
        if parameters.first().and_then(|t| t.text.parse::<i64>().ok()) != Some(entity_type) {
            return Err(IgesError::at(
                cards[0].line,
                format!("entity {entity_type} at DE {de}: its parameters start with another type"),
            ));
        }
        entities.push(RawEntity {
            de,
            line: a.line,
            entity_type,
            form,
            transform: usize::try_from(transform).unwrap_or(0),
            status,
            colour,
            parameters,
        });
    }
    Ok(RawFile { global, entities })
}
