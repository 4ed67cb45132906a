use super::*;

/// A curl: 2 cm straight out of the scalp along local +Y, then a helix of
/// radius `a` about an axis parallel to +Y.
fn curl(a: f32) -> Vec<V3> {
    let mut points = vec![[0.0, 0.0, 0.0], [0.0, 0.02, 0.0]];
    for k in 1..=60 {
        let phi = k as f32 * 0.4;
        points.push([a * phi.cos() - a, 0.02 + 0.004 * phi, a * phi.sin()]);
    }
    points
}

/// Three guides with the same curl in their root frames, rooted on a
/// 10 cm sphere at 35 degrees from the pole, 120 degrees apart.
fn three_curled_guides(a: f32) -> Groom {
    let up = [0.0, 1.0, 0.0];
    let strands: Vec<Vec<V3>> = (0..3)
        .map(|k| {
            let polar = 35f32.to_radians();
            let azimuth = (120.0 * k as f32).to_radians();
            let normal = [
                polar.sin() * azimuth.cos(),
                polar.cos(),
                polar.sin() * azimuth.sin(),
            ];
            let root = scale(normal, 0.1);
            let turn = MinimalRotation::new(up, normal);
            curl(a).iter().map(|&p| add(root, turn.apply(p))).collect()
        })
        .collect();
    Groom::from_strands(strands)
}

/// Mean circumradius of consecutive point triples (the curl's radius of
/// curvature).
fn curl_radius(points: &[V3]) -> f32 {
    let radii: Vec<f32> = points[3..]
        .windows(3)
        .map(|w| {
            let (a, b, c) = (sub(w[1], w[0]), sub(w[2], w[1]), sub(w[2], w[0]));
            let area2 = dot(cross(a, c), cross(a, c)).sqrt();
            dot(a, a).sqrt() * dot(b, b).sqrt() * dot(c, c).sqrt() / (2.0 * area2)
        })
        .collect();
    radii.iter().sum::<f32>() / radii.len() as f32
}

fn max_distance(a: &[V3], b: &[V3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(&p, &q)| dot(sub(p, q), sub(p, q)).sqrt())
        .fold(0.0, f32::max)
}

#[test]
fn a_strand_rooted_on_a_guide_root_is_that_guide() {
    let guides = three_curled_guides(0.01);
    let strands: Vec<&[V3]> = guides.strands().collect();
    let roots: Vec<V3> = strands.iter().map(|s| s[0]).collect();
    let counts = vec![guides.strand_vertex_counts[0]; 3];
    let hair = RenderHair::nearest(&guides, &roots, counts, InterpolationOptions::default());
    assert_eq!(hair.weights[1], [1.0, 0.0, 0.0]);
    let points = hair.points(&guides.strand_vertex_counts, &guides.points);
    assert!(max_distance(&points, &guides.points) < 1e-6);
}

#[test]
fn three_guides_with_one_curl_give_that_curl() {
    let radius = 0.01;
    let guides = three_curled_guides(radius);
    let n = guides.strand_vertex_counts[0];
    let pole = [0.0, 0.1, 0.0];
    let hair = RenderHair::linked(
        &guides,
        &[pole],
        vec![[0, 1, 2]],
        vec![[1.0 / 3.0; 3]],
        vec![n],
        InterpolationOptions::default(),
    );
    let strand = hair.points(&guides.strand_vertex_counts, &guides.points);
    let guide_radius = curl_radius(guides.strands().next().unwrap());
    let render_radius = curl_radius(&strand);
    let error = (render_radius / guide_radius - 1.0).abs();
    assert!(
        error < 0.05,
        "curl radius {render_radius} vs {guide_radius}"
    );
    assert!(dot(sub(strand[0], pole), sub(strand[0], pole)) < 1e-12);

    // Blending world positions (offset to the same root) shrinks the curl:
    // the test above tells the two apart.
    let guide_strands: Vec<&[V3]> = guides.strands().collect();
    let naive: Vec<V3> = (0..n as usize)
        .map(|i| {
            let mut p = pole;
            for s in &guide_strands {
                p = add(p, scale(sub(s[i], s[0]), 1.0 / 3.0));
            }
            p
        })
        .collect();
    let naive_error = (curl_radius(&naive) / guide_radius - 1.0).abs();
    assert!(
        naive_error > 0.05,
        "naive blending kept the curl: {naive_error}"
    );
}

#[test]
fn render_strands_turn_with_their_guides() {
    let guides = three_curled_guides(0.01);
    let hair = RenderHair::grow(
        &guides,
        20,
        InterpolationOptions {
            clump: 0.3,
            noise: 0.002,
            seed: 7,
        },
    );
    let before = hair.points(&guides.strand_vertex_counts, &guides.points);
    // Turn the whole groom a quarter turn about Z: the render hair turns along.
    let turn = |p: V3| [-p[1], p[0], p[2]];
    let turned: Vec<V3> = guides.points.iter().map(|&p| turn(p)).collect();
    let after = hair.points(&guides.strand_vertex_counts, &turned);
    let expected: Vec<V3> = before.iter().map(|&p| turn(p)).collect();
    assert!(max_distance(&after, &expected) < 1e-5);
}

#[test]
fn grown_roots_lie_in_guide_triangles_with_barycentric_weights() {
    let guides = three_curled_guides(0.01);
    let options = InterpolationOptions {
        seed: 3,
        ..InterpolationOptions::default()
    };
    let hair = RenderHair::grow(&guides, 50, options);
    assert_eq!(hair, RenderHair::grow(&guides, 50, options));
    let points = hair.points(&guides.strand_vertex_counts, &guides.points);
    let roots: Vec<V3> = guides.strands().map(|s| s[0]).collect();
    let mut start = 0;
    for (r, &n) in hair.counts.iter().enumerate() {
        let w = hair.weights[r];
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(w.iter().all(|&x| x >= 0.0) && w[0] >= w[1] && w[1] >= w[2]);
        let mut expected = [0.0; 3];
        for (&g, &wk) in hair.closest[r].iter().zip(&w) {
            expected = add(expected, scale(roots[g as usize], wk));
        }
        assert!(max_distance(&[points[start]], &[expected]) < 1e-6);
        start += n as usize;
    }
}

#[test]
fn detail_is_kept_at_rest() {
    let guides = three_curled_guides(0.01);
    let other = three_curled_guides(0.012);
    let roots: Vec<V3> = other.strands().map(|s| s[0]).collect();
    let hair = RenderHair::nearest(
        &guides,
        &roots,
        other.strand_vertex_counts.clone(),
        InterpolationOptions::default(),
    )
    .with_detail(&guides, &other.points);
    let points = hair.points(&guides.strand_vertex_counts, &guides.points);
    assert!(max_distance(&points, &other.points) < 1e-6);
}

#[test]
fn strands_interpolated_in_parallel_runs_match_one_thread_and_keep_their_own_detail() {
    let guides = three_curled_guides(0.01);
    // Several runs of strands, the last one partial.
    let count = 3 * STRANDS_PER_RUN + 17;
    let options = InterpolationOptions {
        clump: 0.3,
        noise: 0.002,
        seed: 5,
    };
    let hair = RenderHair::grow(&guides, count, options);
    let plain = hair.points(&guides.strand_vertex_counts, &guides.points);
    // A detail of its own at every vertex: a strand that read another
    // strand's detail would not come back to these points.
    let target: Vec<V3> = plain
        .iter()
        .enumerate()
        .map(|(i, &p)| add(p, [1e-4 * (i % 7) as f32, 0.0, 2e-5 * (i % 3) as f32]))
        .collect();
    let hair = hair.with_detail(&guides, &target);
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| hair.points(&guides.strand_vertex_counts, &guides.points))
    };
    let (one, three) = (on(1), on(3));
    assert_eq!(one.len(), hair.vertex_count());
    let bits =
        |points: &[V3]| -> Vec<[u32; 3]> { points.iter().map(|p| p.map(f32::to_bits)).collect() };
    assert_eq!(bits(&one), bits(&three));
    assert!(max_distance(&one, &target) < 1e-6);
}
