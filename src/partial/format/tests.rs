//! The partial file format's tests: exact round trips, old versions,
//! and every way a file can be cut, corrupted or oversized.

use super::*;

fn sample_partial() -> Partial {
    let mut film = Film::new(3, 2);
    for i in 0..6 {
        film.sums[i] = [
            i as i128 * 1_000_000_007,
            -(i as i128),
            i128::MAX - i as i128,
        ];
        film.counts[i] = 10 + i as u32;
    }
    film.invalid = 4;
    film.clamped = 1;
    film.first_invalid = Some(BadSample {
        x: 2,
        y: 1,
        sample: 7,
    });
    Partial {
        header: PartialHeader {
            strata_version: "0.1.0".into(),
            scene_hash: 0x0123_4567_89ab_cdef,
            width: 3,
            height: 2,
            spp: 16,
            seed: 9,
            sampler: SamplerKind::Stratified,
            shadow_samples: 4,
            reflection_samples: 2,
            max_depth: 5,
            slices: 1..2,
            slice_count: 4,
            samples: 4..8,
            exposure: -1.5,
            tonemap: Tonemap::Filmic,
        },
        film,
    }
}

fn bytes(p: &Partial) -> Vec<u8> {
    let mut v = Vec::new();
    write_partial_to(&mut v, &p.header, &p.film).unwrap();
    v
}

fn read(b: &[u8]) -> Result<Partial, String> {
    read_partial_from(b, b.len() as u64)
}

#[test]
fn round_trips_exactly() {
    let p = sample_partial();
    let b = bytes(&p);
    assert_eq!(
        b.len() as u64,
        8 + 4 + 2 + 5 + 8 + 52 + 12 + 16 + 16 + 6 * 52 + 8
    );
    assert_eq!(read(&b).unwrap(), p);
    assert!(p.header.is_complete());
}

/// A `--noise` render's film keeps its squares through a file, and the
/// display of 8-bit outputs is kept whatever the film.
#[test]
fn squares_and_display_round_trip() {
    let mut p = sample_partial();
    assert_eq!(bytes(&p)[8..12], FORMAT_VERSION.to_le_bytes());
    p.film.track_squares();
    for (i, q) in p.film.squares.iter_mut().enumerate() {
        *q = (i as i128 + 1) << 70;
    }
    let b = bytes(&p);
    assert_eq!(b.len(), bytes(&sample_partial()).len() + 6 * 16);
    assert_eq!(read(&b).unwrap(), p);
    assert!(read(&b[..b.len() - 9]).unwrap_err().contains("truncated"));
    p.header.tonemap = Tonemap::Clamp;
    p.header.exposure = 2.25;
    assert_eq!(read(&bytes(&p)).unwrap(), p);
}

/// Files of versions 1 and 2 (written before the display was kept)
/// still read, and show the film as the defaults do.
#[test]
fn versions_one_and_two_still_read() {
    let mut p = sample_partial();
    let old = |p: &Partial, version| {
        let mut v = Vec::new();
        write_version(&mut v, &p.header, &p.film, version).unwrap();
        v
    };
    let one = old(&p, FORMAT_VERSION_PLAIN);
    assert_eq!(one.len() + 12, bytes(&p).len());
    let back = read(&one).unwrap();
    assert_eq!(
        (back.header.exposure, back.header.tonemap),
        (0.0, Tonemap::Clamp)
    );
    assert_eq!(back.film, p.film);
    p.film.track_squares();
    p.film.squares[5] = 77;
    let back = read(&old(&p, FORMAT_VERSION_SQUARES)).unwrap();
    assert_eq!(back.film, p.film);
    let mut v4 = bytes(&p);
    v4[8..12].copy_from_slice(&4u32.to_le_bytes());
    assert!(read(&v4).unwrap_err().contains("reads versions 1 to 3"));
}

#[test]
fn truncation_corruption_and_garbage_are_refused() {
    let b = bytes(&sample_partial());
    for len in [0, 5, 8, 20, 60, b.len() - 60, b.len() - 1] {
        let e = read(&b[..len]).unwrap_err();
        assert!(
            e.contains("truncated") || e.contains("not a strata"),
            "{len}: {e}"
        );
    }
    for i in [0usize, 9, 40, 150, b.len() - 30, b.len() - 3] {
        let mut c = b.clone();
        c[i] ^= 0x04;
        assert!(read(&c).is_err(), "flipped byte {i} accepted");
    }
    let mut longer = b.clone();
    longer.push(0);
    assert!(read(&longer).unwrap_err().contains("corrupt"));
    assert!(read(b"P6\n3 2\n255\n......").is_err());
}

#[test]
fn a_huge_claimed_size_allocates_nothing() {
    let mut p = sample_partial();
    p.header.width = 32768;
    p.header.height = 32768;
    let head = p.header.header_bytes(FORMAT_VERSION, false);
    let mut b = head.clone();
    b.extend_from_slice(&[0u8; 32]);
    let e = read(&b).unwrap_err();
    assert!(e.contains("truncated"), "{e}");
    // Past the largest image a render makes: corrupt, whatever the length.
    p.header.width = 1_000_000;
    let mut b = p.header.header_bytes(FORMAT_VERSION, false);
    b.extend_from_slice(&[0u8; 32]);
    let e = read(&b).unwrap_err();
    assert!(
        e.contains("corrupt header: image size 1000000x32768"),
        "{e}"
    );
}

/// A length that matches the header (a sparse file's may, at any size)
/// is not enough: the film must fit in the memory there is, and the
/// error says so before allocating it.
#[test]
fn a_film_past_the_memory_there_is_is_refused_before_it_is_made() {
    let mut p = sample_partial();
    (p.header.width, p.header.height) = (1000, 1000);
    let mut b = p.header.header_bytes(FORMAT_VERSION, false);
    b.extend_from_slice(&[0u8; 32]);
    let claimed = b.len() as u64 + 1000 * 1000 * PIXEL_BYTES + 8;
    let budget = Some(Budget::given(1 << 20));
    let e = read_within(&b[..], claimed, budget).unwrap_err();
    assert!(
        e.starts_with(
            "its 1000×1000 film (52 bytes a pixel) needs 49.6 MiB, more than the 1.0 MiB allowed"
        ),
        "{e}"
    );
}

#[test]
fn mismatches_name_the_setting() {
    let a = sample_partial().header;
    let mut b = a.clone();
    b.slices = 2..3;
    b.samples = 8..12;
    assert_eq!(a.render_mismatch(&b), None);
    b.seed = 10;
    assert_eq!(a.render_mismatch(&b).unwrap(), "seed: 9 vs 10");
    let mut c = a.clone();
    c.scene_hash ^= 1;
    assert!(a.render_mismatch(&c).unwrap().starts_with("scene"));
}

#[test]
fn another_spp_alone_says_what_to_do_instead() {
    let mut done = sample_partial().header;
    (done.slices, done.slice_count, done.samples) = (0..1, 1, 0..done.spp);
    let mut more = done.clone();
    more.spp = done.spp * 2;
    let e = done.resume_point(&more, false).unwrap_err();
    assert!(e.contains("it is finished"), "{e}");
    assert!(e.contains("--spp 32 --slice 0/2"), "{e}");
    done.samples = 0..8;
    let e = done.resume_point(&more, false).unwrap_err();
    assert!(e.contains("pass --spp 16 to finish it"), "{e}");
    // With another difference as well, that is the message.
    more.seed += 1;
    let e = done.resume_point(&more, false).unwrap_err();
    assert!(
        e.starts_with("the checkpoint is of a different render"),
        "{e}"
    );
}
