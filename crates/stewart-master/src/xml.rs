//! A small element tree over quick-xml for the two documents a master reads: an FMU's
//! `modelDescription.xml` and an SSP's `SystemStructure.ssd`. Names are kept without their
//! namespace prefix (`ssd:Component` is `Component`).

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

#[derive(Debug, Default)]
pub struct Element {
    pub name: String,
    pub attributes: Vec<(String, String)>,
    pub children: Vec<Element>,
}

impl Element {
    pub fn attribute(&self, key: &str) -> Option<&str> {
        self.attributes.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

fn element(start: &BytesStart, reader: &Reader<&[u8]>) -> Result<Element, String> {
    let mut e = Element { name: start.name().local_name().as_ref().to_string(), ..Default::default() };
    for a in start.attributes() {
        let a = a.map_err(|err| format!("bad attribute at byte {}: {err}", reader.buffer_position()))?;
        let value = a.normalized_value(quick_xml::XmlVersion::Implicit1_0).map_err(|err| format!("{err}"))?;
        e.attributes.push((a.key.local_name().as_ref().to_string(), value.into_owned()));
    }
    Ok(e)
}

/// The document's root element.
pub fn parse(text: &str) -> Result<Element, String> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().trim_text(true);
    let mut stack: Vec<Element> = vec![Element::default()];
    loop {
        let event = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML at byte {}: {e}", reader.buffer_position()))?;
        match &event {
            Event::Start(start) => stack.push(element(start, &reader)?),
            Event::Empty(start) => {
                let e = element(start, &reader)?;
                stack.last_mut().ok_or("unbalanced XML")?.children.push(e);
            }
            Event::End(_) => {
                let e = stack.pop().ok_or("unbalanced XML")?;
                stack.last_mut().ok_or("unbalanced XML")?.children.push(e);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let document = stack.pop().filter(|_| stack.is_empty()).ok_or("XML ends inside an element")?;
    document.children.into_iter().next().ok_or_else(|| "an empty XML document".to_string())
}
