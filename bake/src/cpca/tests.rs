//! Clustered PCA: fits, refinement, the error table, the allocation, the covariance.

use super::*;
use crate::sampling::{hash_u32, u32_to_unit};
use crate::work::with_threads;

const P: usize = 300;
const GROUP_SIZES: [u32; 4] = [70, 60, 40, 30];

fn noise(e: u32, dim: u32) -> f32 {
    u32_to_unit(hash_u32(7, e, dim, 0)) - 0.5
}

/// 200 points of P values in four groups at separate 3D positions (the features); a group's
/// rows are a smooth mean plus two smooth modes with random weights plus 1% noise.
fn grouped() -> (Vec<f32>, Vec<f32>) {
    let (mut data, mut features, mut e) = (vec![], vec![], 0);
    for (g, &size) in GROUP_SIZES.iter().enumerate() {
        let g = g as f32;
        for _ in 0..size {
            features.extend([10.0 * g + noise(e, 0), noise(e, 1), 5.0 * g.sin() + noise(e, 2)]);
            let (a, b) = (noise(e, 3), noise(e, 4));
            data.extend((0..P).map(|p| {
                let t = p as f32 / P as f32;
                (t * (g + 1.0)).sin() + a * (7.0 * t + g).cos() + b * (3.0 * t * (g + 1.0)).sin() + 0.01 * noise(e, 5 + p as u32)
            }));
            e += 1;
        }
    }
    (data, features)
}

fn table(counts: &[usize], max_basis: usize) -> Vec<Candidate> {
    let (data, features) = grouped();
    error_table(&data, P, &features, 3, counts, max_basis).unwrap()
}

/// The blocked products are the covariance's and the Gram matrix's entries (against one serial
/// f64 sum each, to rounding), symmetric, and the same bits on one thread as on two: at sizes
/// across a block's edges in both directions, down to a last block of one vector and a last
/// stretch of one value.
#[test]
fn the_blocked_products_are_each_entrys_sum_at_any_thread_count() {
    let values = |n: usize, cols: usize| -> Vec<f32> { (0..n * cols).map(|k| noise(k as u32, 9) + 0.25).collect() };
    let bits = |m: &DMatrix<f64>| -> Vec<u64> { m.iter().map(|v| v.to_bits()).collect() };
    for (members, cols) in [(700usize, 300usize), (57, 70), (4, 33), (300, 1100), (3, 5), (129, 513), (513, 129)] {
        let data = values(members, cols);
        let rows = Rows { values: &data, cols };
        let all: Vec<u32> = (0..members as u32).collect();
        let centred = Centred::new(rows, &all);
        let products = |threads| with_threads(Some(threads), || (centred.covariance(), rows.gram(&all, &Progress::new(0, "", false))));
        let ((covariance, gram), (covariance_2, gram_2)) = (products(1), products(2));
        assert!(
            bits(&covariance) == bits(&covariance_2) && bits(&gram) == bits(&gram_2),
            "{members} x {cols}: the thread count moved a bit"
        );
        let column: Vec<Vec<f64>> =
            (0..cols).map(|k| (0..members).map(|e| (centred.row(e)[k] - centred.mean[k]) as f64).collect()).collect();
        let wide: Vec<Vec<f64>> = (0..members).map(|e| rows.row(e).iter().map(|&v| v as f64).collect()).collect();
        let sum = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(a, b)| a * b).sum() };
        for (product, vectors, scale, what) in [(&covariance, &column, members, "covariance"), (&gram, &wide, cols, "Gram matrix")] {
            for (i, j) in (0..vectors.len()).flat_map(|i| (0..vectors.len()).map(move |j| (i, j))) {
                let (got, expected) = (product[(i, j)], sum(&vectors[i], &vectors[j]));
                assert!(
                    product[(j, i)] == got && (got - expected).abs() <= 1e-12 * scale as f64,
                    "{members} x {cols} {what} ({i}, {j}): {got} against {expected}"
                );
            }
        }
    }
}

/// Every split of 6 vectors among three clusters of unequal spectra, against the greedy's.
#[test]
fn the_variable_allocation_drops_the_least_variance_of_any_split() {
    let spectra: [&[f64]; 3] = [&[9.0, 1.0, 0.5, 0.1], &[4.0, 3.0, 2.0, 1e-15], &[6.0, 0.2]];
    let dropped = |counts: &[usize]| -> f64 { spectra.iter().zip(counts).map(|(s, &d)| s.iter().skip(d).sum::<f64>()).sum() };
    let greedy = allocate(&spectra, 6, 1024);
    assert_eq!(greedy, vec![2, 3, 1]);
    for a in 0..=4 {
        for b in 0..=4usize {
            let c = 6usize.saturating_sub(a + b).min(2);
            if a + b + c == 6 {
                assert!(dropped(&greedy) <= dropped(&[a, b, c]), "{greedy:?} drops more than {:?}", [a, b, c]);
            }
        }
    }
    // Rounding noise gets no vector; a cap holds.
    assert_eq!(allocate(&spectra, 100, 1024), vec![4, 3, 2]);
    assert_eq!(allocate(&spectra, 100, 1), vec![1, 1, 1]);
}

#[test]
fn clusterings_are_nested_and_error_falls_with_c_and_d() {
    let (_, features) = grouped();
    let tree = divisive_clusters(&features, 3, 8);
    for c in 1..tree.max_clusters() {
        let (coarse, fine) = (tree.assignment(c), tree.assignment(c + 1));
        let mut parent = vec![None; c + 1];
        for (&f, &k) in fine.iter().zip(&coarse) {
            assert_eq!(*parent[f as usize].get_or_insert(k), k, "C = {} does not refine C = {c}", c + 1);
        }
    }
    let table = table(&(1..=8).collect::<Vec<_>>(), 6);
    let error = |c: usize, d: usize| table.iter().find(|t| (t.clusters, t.basis) == (c, d)).unwrap().relative_error;
    for c in 1..=8 {
        for d in 0..=6 {
            assert!(d == 0 || error(c, d) <= error(c, d - 1) * (1.0 + 1e-6), "C {c} D {d}");
            assert!(c == 1 || error(c, d) <= error(c - 1, d) * (1.0 + 1e-6), "C {c} D {d}");
        }
    }
    assert!(error(4, 2) < 0.1 * error(1, 2), "the four groups are found: {}", error(4, 2));
}

#[test]
fn predicted_error_matches_a_fit() {
    let (data, features) = grouped();
    let table = table(&[1, 3, 4, 7], 5);
    for (c, d) in [(1, 0), (1, 5), (3, 2), (4, 2), (7, 5)] {
        let predicted = table.iter().find(|t| (t.clusters, t.basis) == (c, d)).unwrap().relative_error;
        let actual = fit(&data, P, &features, 3, c, d).unwrap().relative_error(&data);
        assert!((predicted - actual).abs() <= 1e-4 * actual, "C {c} D {d}: {predicted} vs {actual}");
    }
}

#[test]
fn basis_as_large_as_the_clusters_is_exact() {
    let (data, features) = grouped();
    let largest = fit(&data, P, &features, 3, 4, 0).unwrap().clusters.iter().map(|c| c.members.len()).max();
    let cpca = fit(&data, P, &features, 3, 4, largest.unwrap()).unwrap();
    assert!(cpca.relative_error(&data) < 1e-5, "{}", cpca.relative_error(&data));
}

#[test]
fn choose_takes_the_smallest_within_budget() {
    let table = table(&[1, 2, 4, 6], 4);
    let budget = table.iter().find(|t| (t.clusters, t.basis) == (4, 2)).unwrap().relative_error * 1.01;
    let chosen = choose(&table, budget).unwrap();
    assert!(chosen.relative_error <= budget);
    assert!(table.iter().all(|t| t.relative_error > budget || t.stored_values >= chosen.stored_values));
    assert_eq!(choose(&table, -1.0), None);
    assert_eq!(choose(&table[..5], 1e-9), None, "C = 1 cannot hold four groups plus noise");
    let candidate = |basis, relative_error| Candidate { clusters: 1, basis, relative_error, stored_values: 10 };
    let tied = [candidate(1, 0.3), candidate(2, 0.2), Candidate { stored_values: 11, ..candidate(3, 0.1) }];
    assert_eq!(choose(&tied, 0.5), Some(tied[1]));
    assert_eq!(choose(&tied, 0.15), Some(tied[2]));
}

#[test]
fn two_lines_need_two_clusters_of_one_vector() {
    // Points 0..4 on the line (1 + t, 2, 3), points 4..8 on (0, 5 + t, 5 + t), apart in features.
    let data: Vec<f32> = (0..8)
        .flat_map(|e| {
            let t = (e % 4) as f32;
            if e < 4 {
                [1.0 + t, 2.0, 3.0]
            } else {
                [0.0, 5.0 + t, 5.0 + t]
            }
        })
        .collect();
    let features: Vec<f32> = (0..8).flat_map(|e| [if e < 4 { 0.0 } else { 10.0 }, 0.1 * e as f32]).collect();
    let cpca = fit(&data, 3, &features, 2, 2, 3).unwrap();
    assert_eq!(cpca.assignment, [0, 0, 0, 0, 1, 1, 1, 1]);
    assert!(cpca.relative_error(&data) < 1e-6);
    let first = &cpca.clusters[0];
    assert_eq!(first.mean, [2.5, 2.0, 3.0]);
    let sign = first.basis[0][0].signum();
    assert!(first.basis[0].iter().zip([1.0, 0.0, 0.0]).all(|(b, x)| (b - sign * x).abs() < 1e-6));
    for (k, w) in first.weights.iter().enumerate() {
        assert!((w[0] - sign * (k as f32 - 1.5)).abs() < 1e-6 && w[1..] == [0.0, 0.0], "{w:?}");
    }
    assert!(first.basis[1..].iter().all(|b| b == &[0.0; 3]), "rank 1: the rest are zero vectors");
    let half = std::f32::consts::FRAC_1_SQRT_2;
    assert!(cpca.clusters[1].basis[0].iter().zip([0.0, half, half]).all(|(b, x)| (b.abs() - x).abs() < 1e-6));
}

#[test]
fn same_bytes_whatever_the_thread_count() {
    let (data, features) = grouped();
    let run = |threads| with_threads(Some(threads), || fit(&data, P, &features, 3, 5, 3).unwrap());
    assert_eq!(run(1), run(2));
}

/// The grouped points cut to their first 20 values: clusters of more members than values,
/// which take the covariance route.
fn narrow() -> (Vec<f32>, Vec<f32>) {
    let (data, features) = grouped();
    (data.chunks_exact(P).flat_map(|row| row[..20].to_vec()).collect(), features)
}

#[test]
fn the_covariance_route_predicts_its_fit_and_is_exact_at_full_rank() {
    let (data, features) = narrow();
    let table = error_table(&data, 20, &features, 3, &[1, 4], 20).unwrap();
    for (c, d) in [(1, 0), (1, 3), (4, 2), (4, 5)] {
        let predicted = table.iter().find(|t| (t.clusters, t.basis) == (c, d)).unwrap().relative_error;
        let actual = fit(&data, 20, &features, 3, c, d).unwrap().relative_error(&data);
        assert!((predicted - actual).abs() <= 1e-4 * actual, "C {c} D {d}: {predicted} vs {actual}");
    }
    assert!(fit(&data, 20, &features, 3, 4, 20).unwrap().relative_error(&data) < 1e-5);
}

/// Clustered by features that mix the four groups, refinement moves points to the clusters
/// that reconstruct them and the error falls round by round, never rising.
#[test]
fn refinement_never_raises_the_error() {
    let (data, _) = grouped();
    let misleading: Vec<f32> = (0..data.len() / P).map(|e| noise(e as u32, 99)).collect();
    let first = fit(&data, P, &misleading, 1, 4, 2).unwrap();
    let errors: Vec<f64> = (0..6).map(|rounds| refine(&data, P, first.clone(), rounds).0.relative_error(&data)).collect();
    println!("relative error after 0..6 rounds: {errors:?}");
    assert!(errors.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-9)), "{errors:?}");
    assert!(errors[5] < 0.5 * errors[0], "{errors:?}");
    let (settled, rounds) = refine(&data, P, first, 100);
    assert!(rounds < 100 && refine(&data, P, settled.clone(), 100) == (settled, 0), "it settles");
}

#[test]
fn refuses_bad_input() {
    let (data, features) = ([1.0, 2.0, 3.0, 4.0], [0.0, 1.0]);
    let refusal = |data: &[f32], features: &[f32], clusters| fit(data, 2, features, 1, clusters, 1).unwrap_err();
    assert!(refusal(&[], &[], 1).contains("no data"));
    assert!(refusal(&data[..3], &features, 1).contains("not whole rows"));
    assert!(refusal(&data, &features[..1], 1).contains("features hold 1"));
    assert!(refusal(&data, &features, 0).contains("cluster counts [0]"));
    assert!(refusal(&data, &features, 3).contains("cluster counts [3]"));
    assert!(refusal(&[1.0, 2.0, 3.0, f32::NAN], &features, 1).contains("data row 1"));
    assert!(refusal(&data, &[0.0, f32::INFINITY], 1).contains("features row 1"));
    assert!(error_table(&data, 2, &features, 1, &[], 1).unwrap_err().contains("cluster counts []"));
}
