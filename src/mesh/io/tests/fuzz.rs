//! Any bytes give `Ok` or `Err`, never a panic: random bytes, token soups that reach deep
//! into the text parsers, and mutations (bit flips, truncation, lying numbers) of valid files.

use proptest::prelude::*;
use proptest::sample::Index;
use serde_json::json;

use super::gltf_doc::{Doc, glb_container, tetra_arrays};
use super::{ascii_stl, binary_stl, cube, cube_obj};
use crate::mesh::io::{Format, GlbBuilder, Units, read_mesh_bytes};

/// Cases per property: 512, or `WAVEMILL_FUZZ_CASES` for a longer run.
fn fuzz_cases() -> u32 {
    std::env::var("WAVEMILL_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(512)
}

const FORMATS: [Format; 4] = [Format::Stl, Format::Obj, Format::Gltf, Format::Glb];

fn try_all(bytes: &[u8]) {
    for f in FORMATS {
        // Units::Metres also exercises overflow by scaling.
        let r = read_mesh_bytes(bytes, f, "fuzz", None, Units::Metres);
        if let Ok(r) = r {
            let n = r.mesh.positions.len();
            assert!(!r.mesh.triangles.is_empty());
            assert!(r.mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
            assert!(
                r.mesh
                    .positions
                    .iter()
                    .all(|p| p.iter().all(|c| c.is_finite()))
            );
        }
    }
}

/// A glTF scene with most features: nested transforms, strip, fan, lines, sparse, quantized
/// strided positions.
fn rich_doc() -> Doc {
    let mut d = Doc::default();
    let (pts, idx) = tetra_arrays();
    let p = d.positions(&pts);
    let i = d.indices_u16(&idx);
    let s = d.indices_u32(&[0, 1, 2, 3, 3, 3, 0, 1]);
    d.mesh(vec![
        Doc::prim(p, Some(i), 4),
        Doc::prim(p, Some(s), 5),
        Doc::prim(p, Some(s), 6),
        Doc::prim(p, None, 1),
    ]);
    let q = d.positions(&pts);
    d.sparse_replace(q, 1, [2.0, 0.0, 0.0]);
    d.mesh(vec![Doc::prim(q, None, 4)]);
    let r = d.positions_i16(&[[0, 0, 0], [32767, 0, 0], [0, -32768, 0], [0, 0, 1000]]);
    d.mesh(vec![Doc::prim(r, Some(i), 4)]);
    d.node(json!({ "translation": [1.0, 2.0, 3.0], "children": [1, 2, 3] }));
    d.node(json!({ "mesh": 0, "scale": [-1.0, 1.0, 1.0] }));
    d.node(json!({ "mesh": 1, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 5,0,0,1] }));
    d.node(json!({ "mesh": 2, "rotation": [0.0, 0.6, 0.0, 0.8] }));
    d.scenes = Some(vec![vec![0]]);
    d
}

fn seeds() -> Vec<(Format, Vec<u8>)> {
    let mut b = GlbBuilder::new();
    b.add_triangles("cube", &cube(), [1.0; 4], Some(&[[0.5; 4]; 8]))
        .unwrap()
        .add_polylines(
            "p",
            &[vec![
                nalgebra::Point3::origin(),
                nalgebra::Point3::new(1.0, 1.0, 1.0),
            ]],
            [1.0; 4],
        )
        .unwrap();
    let d = rich_doc();
    vec![
        (Format::Stl, binary_stl(&cube(), "solid header")),
        (Format::Stl, ascii_stl(&cube(), "c")),
        (Format::Obj, cube_obj().into_bytes()),
        (Format::Gltf, d.gltf_data_uri()),
        (Format::Glb, d.glb()),
        (Format::Glb, b.build()),
    ]
}

fn prefix() -> impl Strategy<Value = &'static [u8]> {
    prop::sample::select(vec![
        &b""[..],
        b"solid ",
        b"glTF\x02\0\0\0",
        b"{",
        b"v 0 0 0\n",
        b"solid x\nfacet normal 0 0 1\nouter loop\n",
    ])
}

fn token_soup() -> impl Strategy<Value = Vec<u8>> {
    let words = prop::sample::select(vec![
        "solid",
        "endsolid",
        "facet",
        "normal",
        "outer",
        "loop",
        "vertex",
        "endloop",
        "endfacet",
        "v",
        "vt",
        "vn",
        "f",
        "l",
        "p",
        "o",
        "g",
        "usemtl",
        "mtllib",
        "#",
        "1",
        "-1",
        "0",
        "3",
        "2.5",
        "-0",
        "1e308",
        "-1e309",
        "nan",
        "inf",
        "1/1/1",
        "1//1",
        "-9223372036854775808",
        "99999999999999999999",
        "/",
        "\n",
        "\r\n",
        "\t",
        "x",
    ]);
    prop::collection::vec(words, 0..200).prop_map(|w| w.join(" ").into_bytes())
}

/// Numbers that lengths, offsets, counts and indices might lie with.
fn lying_number() -> impl Strategy<Value = &'static str> {
    prop::sample::select(vec![
        "0",
        "1",
        "2",
        "3",
        "4",
        "5",
        "7",
        "8",
        "12",
        "255",
        "256",
        "65535",
        "65536",
        "4294967295",
        "4294967296",
        "9007199254740993",
        "18446744073709551615",
        "99999999999999999999999",
        "-1",
        "1e40",
        "0.5",
        "5120",
        "5121",
        "5122",
        "5123",
        "5125",
        "5126",
    ])
}

/// Replaces some digit runs of `json` with lying numbers.
fn mutate_numbers(json: &[u8], picks: &[(Index, &str)]) -> Vec<u8> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < json.len() {
        if json[i].is_ascii_digit() {
            let start = i;
            while i < json.len() && json[i].is_ascii_digit() {
                i += 1;
            }
            runs.push((start, i));
        } else {
            i += 1;
        }
    }
    let mut chosen: Vec<(usize, usize, &str)> = picks
        .iter()
        .filter(|_| !runs.is_empty())
        .map(|(ix, s)| {
            let (a, b) = runs[ix.index(runs.len())];
            (a, b, *s)
        })
        .collect();
    chosen.sort_by_key(|c| std::cmp::Reverse(c.0));
    chosen.dedup_by_key(|c| c.0);
    let mut out = json.to_vec();
    for (a, b, s) in chosen {
        out.splice(a..b, s.bytes());
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(fuzz_cases()))]

    #[test]
    fn random_bytes_never_panic(p in prefix(), tail in prop::collection::vec(any::<u8>(), 0..600)) {
        let mut bytes = p.to_vec();
        bytes.extend(tail);
        try_all(&bytes);
    }

    #[test]
    fn token_soups_never_panic(p in prefix(), soup in token_soup()) {
        let mut bytes = p.to_vec();
        bytes.extend(soup);
        try_all(&bytes);
    }

    #[test]
    fn mutated_valid_files_never_panic(
        seed in any::<Index>(),
        flips in prop::collection::vec((any::<Index>(), any::<u8>()), 0..6),
        cut in prop::option::of(any::<Index>()),
    ) {
        let seeds = seeds();
        let (format, mut bytes) = seeds[seed.index(seeds.len())].clone();
        for (at, x) in flips {
            let i = at.index(bytes.len());
            bytes[i] ^= x;
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len() + 1));
        }
        let _ = read_mesh_bytes(&bytes, format, "fuzz", None, Units::Millimetres);
        try_all(&bytes);
    }

    #[test]
    fn gltf_with_lying_numbers_never_panics(
        picks in prop::collection::vec((any::<Index>(), lying_number()), 1..5),
    ) {
        let d = rich_doc();
        let json = mutate_numbers(&d.glb_json(), &picks);
        let glb = glb_container(&json, &d.bin);
        let _ = read_mesh_bytes(&glb, Format::Glb, "fuzz", None, Units::Millimetres);
        let text = mutate_numbers(&d.gltf_data_uri(), &picks);
        let _ = read_mesh_bytes(&text, Format::Gltf, "fuzz", None, Units::Millimetres);
    }
}
