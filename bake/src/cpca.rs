//! Clustered PCA, the compression of Umenhoffer et al.'s light path maps (000 §3.2.3), after
//! Sloan et al. 2003, "Clustered Principal Components for Precomputed Radiance Transfer".
//!
//! N points (rows) of P values, each with a feature vector used only to cluster (for light path
//! maps the entry point's position and normal, scaled by the caller). Cluster c keeps its mean
//! M^c and the D eigenvectors B^c_d of largest eigenvalue of its covariance, point e its
//! coordinates w^e_d = (x_e - M^c) . B^c_d: x_e ~ M^c + sum_d w^e_d B^c_d. Nothing here knows
//! about textures; per-vertex data works the same.
//!
//! Clustering is divisive, so the clustering for C + 1 refines the one for C and the error only
//! falls as C grows (as it does with D). PCA works on the smaller of the n_c x n_c Gram matrix
//! of the centred points (light path maps: P ~ 50,000 texels, n_c ~ hundreds) and the P x P
//! covariance (light clouds: P = 3 x cloud lights ~ hundreds, n_c ~ thousands of vertices);
//! both share their non-zero eigenvalues, and the squared residual of D basis vectors is the sum of the
//! eigenvalues beyond D, so [`error_table`] rates every (C, D) from eigenvalues alone and
//! [`choose`] picks the cheapest within an error budget. No randomness, and parallel results
//! are independent serial sums: the same bytes whatever the thread count.

use crate::work::Progress;
use faer::linalg::matmul::matmul;
use faer::{Mat, MatRef, Parallelism};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::Range;

mod eigen;
use eigen::{eigen_decomposition, leading_eigenpairs, symmetric_eigenvalues, LEADING_ONLY_SIDE};

/// Lloyd iterations per 2-means split at most; they usually settle in a handful.
const LLOYD_ITERATIONS: usize = 100;
/// Eigenvalues below this fraction of the largest are rounding noise: no basis vector for them.
const RANK_TOLERANCE: f64 = 1e-12;
/// Columns per parallel task when a basis vector is built.
const COLUMN_CHUNK: usize = 1024;
/// Vectors a side of a block of [`products`], and values of each read at a time: a block pair's
/// two stretches (2 x 128 x 512 f64, 1 MiB) stay in a core's cache while they are multiplied.
const BLOCK_VECTORS: usize = 128;
const BLOCK_DEPTH: usize = 512;

/// Row-major points of `cols` values each.
#[derive(Clone, Copy)]
struct Rows<'a> {
    values: &'a [f32],
    cols: usize,
}

impl Rows<'_> {
    fn row(&self, e: usize) -> &[f32] {
        &self.values[e * self.cols..][..self.cols]
    }

    /// G = X X^T of the rows `members` (cost n_c^2 P / 2 in all), by [`products`]. A step of
    /// `progress` per entry of the lower triangle.
    fn gram(&self, members: &[u32], progress: &Progress) -> DMatrix<f64> {
        let fill = |vectors: Range<usize>, depth: Range<usize>, out: &mut [f64]| {
            for (i, out) in vectors.zip(out.chunks_exact_mut(depth.len())) {
                out.iter_mut().zip(&self.row(members[i] as usize)[depth.clone()]).for_each(|(o, &x)| *o = x as f64);
            }
        };
        products(members.len(), self.cols, Layout::ByVector, fill, progress)
    }

    fn mean(&self, members: &[u32]) -> Vec<f64> {
        let mut sum = vec![0.0; self.cols];
        for &e in members {
            sum.iter_mut().zip(self.row(e as usize)).for_each(|(s, &v)| *s += v as f64);
        }
        sum.iter().map(|s| s / members.len() as f64).collect()
    }

    fn distance2(&self, e: u32, to: &[f64]) -> f64 {
        self.row(e as usize).iter().zip(to).map(|(&v, &t)| (v as f64 - t).powi(2)).sum()
    }

    /// Sum of squared distances to the centroid: the cluster to split next has the largest.
    fn scatter(&self, members: &[u32]) -> f64 {
        let centroid = self.mean(members);
        members.iter().map(|&e| self.distance2(e, &centroid)).sum()
    }

    /// The first member farthest from `from`.
    fn farthest(&self, members: &[u32], from: &[f64]) -> u32 {
        let distance = |e: u32| self.distance2(e, from);
        members.iter().copied().reduce(|a, b| if distance(b) > distance(a) { b } else { a }).unwrap()
    }

    /// Members nearer `centres[0]` (ties included), then the others.
    fn nearest(&self, members: &[u32], centres: &[Vec<f64>; 2]) -> (Vec<u32>, Vec<u32>) {
        members.iter().copied().partition(|&e| self.distance2(e, &centres[0]) <= self.distance2(e, &centres[1]))
    }

    /// 2-means by Lloyd iterations, seeded with the member farthest from the centroid and the
    /// member farthest from that (distinct whenever the scatter is positive, and each the
    /// nearest to itself, so both halves start non-empty).
    fn two_means(&self, members: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let widen = |e: u32| self.row(e as usize).iter().map(|&v| v as f64).collect::<Vec<_>>();
        let a = self.farthest(members, &self.mean(members));
        let b = self.farthest(members, &widen(a));
        let mut halves = self.nearest(members, &[widen(a), widen(b)]);
        for _ in 0..LLOYD_ITERATIONS {
            let next = self.nearest(members, &[self.mean(&halves.0), self.mean(&halves.1)]);
            // An empty half can only come from rounding; keep the last proper split then.
            if next == halves || next.0.is_empty() || next.1.is_empty() {
                break;
            }
            halves = next;
        }
        halves
    }
}

/// The nested clusterings of [`divisive_clusters`]: one for every cluster count up to
/// [`ClusterTree::max_clusters`], each refining the one before.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterTree {
    points: usize,
    /// Split k (from k + 1 to k + 2 clusters) moved these points (ascending) to new cluster k + 1.
    splits: Vec<Vec<u32>>,
}

impl ClusterTree {
    /// The clusters asked for, or fewer where the features ran out of distinct points.
    pub fn max_clusters(&self) -> usize {
        self.splits.len() + 1
    }

    /// Cluster id (0..clusters) per point. Panics unless 1 <= clusters <= max_clusters().
    pub fn assignment(&self, clusters: usize) -> Vec<u32> {
        assert!((1..=self.max_clusters()).contains(&clusters), "no clustering into {clusters} clusters");
        let mut ids = vec![0; self.points];
        for (k, moved) in self.splits[..clusters - 1].iter().enumerate() {
            moved.iter().for_each(|&e| ids[e as usize] = k as u32 + 1);
        }
        ids
    }
}

/// Divisive clustering of the points `features` (row-major, `feature_dims` per point): from
/// one cluster, the cluster of largest feature scatter is split in two by 2-means until there
/// are `clusters` clusters or none has two distinct points. Splitting rather than plain
/// k-means makes the clustering for C + 1 a refinement of the one for C, so the PCA error can
/// only fall as C grows, and one tree serves every C. Panics on no points.
pub fn divisive_clusters(features: &[f32], feature_dims: usize, clusters: usize) -> ClusterTree {
    assert!(feature_dims > 0 && !features.is_empty() && features.len().is_multiple_of(feature_dims), "no points");
    let points = Rows { values: features, cols: feature_dims };
    let count = features.len() / feature_dims;
    let mut members = vec![(0..count as u32).collect::<Vec<_>>()];
    let mut scatter = vec![points.scatter(&members[0])];
    let mut splits = vec![];
    while members.len() < clusters {
        // max_by keeps the last of equals: reversed, ties go to the lowest cluster id.
        let (k, &widest) = scatter.iter().enumerate().rev().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
        if widest <= 0.0 {
            break;
        }
        let (stay, moved) = points.two_means(&members[k]);
        scatter[k] = points.scatter(&stay);
        scatter.push(points.scatter(&moved));
        members[k] = stay;
        members.push(moved.clone());
        splits.push(moved);
    }
    ClusterTree { points: count, splits }
}

/// The PCA of one cluster (000 §3.2.3): its mean, eigen-"textures" and members' coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterPca {
    /// Point indices, ascending.
    pub members: Vec<u32>,
    /// M^c: P values.
    pub mean: Vec<f32>,
    /// Every eigenvalue of the centred Gram matrix (n_c of them) or, for clusters of more
    /// members than values per row, of the covariance (P of them: the same non-zero ones),
    /// descending, clamped to >= 0: the squared residual of keeping D basis vectors is the sum
    /// of those beyond D. A matrix wider than 2,048 gives its D + 8 largest alone
    /// (`eigen::leading_eigenpairs`).
    pub eigenvalues: Vec<f64>,
    /// Always D unit P-vectors B^c_d by descending eigenvalue (the D asked of `cluster_pca`).
    /// Where the cluster's rank is below D (at most D points, or points on a flatter subspace)
    /// the rest are zero vectors, so every cluster of one `fit` stores the same D.
    pub basis: Vec<Vec<f32>>,
    /// Per member (in `members` order) its D coordinates w^e_d = (x_e - M^c) . B^c_d (0 for a
    /// zero basis vector).
    pub weights: Vec<Vec<f32>>,
}

/// A cluster: its members' rows, read in place (a centred copy would double the peak memory
/// of a bake whose rows are most of it), and their mean; every product is of the rows minus
/// the mean, formed from the rows' own products.
struct Centred<'a> {
    rows: Rows<'a>,
    members: &'a [u32],
    mean: Vec<f32>,
}

impl<'a> Centred<'a> {
    fn new(rows: Rows<'a>, members: &'a [u32]) -> Centred<'a> {
        assert!(!members.is_empty(), "a cluster needs members");
        let mean: Vec<f32> = rows.mean(members).iter().map(|&m| m as f32).collect();
        Centred { rows, members, mean }
    }

    fn row(&self, e: usize) -> &[f32] {
        self.rows.row(self.members[e] as usize)
    }

    /// G = (X - m)(X - m)^T, from the members' uncentred Gram matrix (`centred`).
    fn gram(&self) -> DMatrix<f64> {
        let uncentred = self.rows.gram(self.members, &Progress::new(0, "", false));
        centred(&uncentred, &(0..self.members.len() as u32).collect::<Vec<_>>())
    }

    /// C = (X - m)^T (X - m) (P x P): the covariance route, for clusters of more members than
    /// values per row (per-vertex transfer: thousands of vertices, hundreds of values), by
    /// [`products`] of the centred columns.
    fn covariance(&self) -> DMatrix<f64> {
        let fill = |columns: Range<usize>, depth: Range<usize>, out: &mut [f64]| {
            let mean = &self.mean[columns.clone()];
            for (member, out) in depth.zip(out.chunks_exact_mut(columns.len())) {
                let row = &self.row(member)[columns.clone()];
                out.iter_mut().zip(row.iter().zip(mean)).for_each(|(o, (&x, &m))| *o = (x - m) as f64);
            }
        };
        products(self.rows.cols, self.members.len(), Layout::ByDepth, fill, &Progress::new(0, "", false))
    }

    /// (X - m)^T v normalised, as X^T v - (sum v) m: an eigenvector v of G with eigenvalue
    /// lambda gives the covariance's eigenvector (X - m)^T v / sqrt(lambda) (Sloan et al. 2003);
    /// normalising directly is the same in exact arithmetic and keeps unit length under
    /// rounding.
    fn basis_vector(&self, v: &[f64]) -> Vec<f32> {
        let total: f64 = v.iter().sum();
        let mut b = vec![0.0f64; self.rows.cols];
        b.par_chunks_mut(COLUMN_CHUNK).enumerate().for_each(|(k, chunk)| {
            for (e, &ve) in v.iter().enumerate() {
                let row = &self.row(e)[k * COLUMN_CHUNK..];
                chunk.iter_mut().zip(row).for_each(|(acc, &x)| *acc += ve * x as f64);
            }
            let mean = &self.mean[k * COLUMN_CHUNK..];
            chunk.iter_mut().zip(mean).for_each(|(acc, &m)| *acc -= total * m as f64);
        });
        let norm = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        b.iter().map(|x| (x / norm) as f32).collect()
    }

    /// (x_e - m) . b, as x_e . b - m . b.
    fn weight(&self, e: usize, b: &[f32], mean_dot: f64) -> f32 {
        (dot(self.row(e), b) - mean_dot) as f32
    }
}

/// How the `fill` of [`products`] lays its block out: a vector's stretch after another (rows of
/// points: the Gram matrix) or, for each value of the stretch, the vectors' values in turn
/// (columns of points: the covariance). Each fill then reads its points in their own order: a
/// covariance filled a vector after another read each row a block's width at a time, and spent
/// more than its products did.
#[derive(Clone, Copy)]
enum Layout {
    ByVector,
    ByDepth,
}

impl Layout {
    /// A filled block as the depth x vectors matrix V of its stretch.
    fn block(self, values: &[f64], depth: usize, vectors: usize) -> MatRef<'_, f64> {
        match self {
            Layout::ByVector => faer::mat::from_column_major_slice::<f64>(values, depth, vectors),
            Layout::ByDepth => faer::mat::from_row_major_slice::<f64>(values, depth, vectors),
        }
    }
}

/// S = V^T V, V the depth x count matrix of `count` vectors of `depth` values each, where
/// `fill(vectors, stretch, out)` writes the values `stretch` of each of `vectors` into `out`,
/// laid out by `layout`. By blocks of vectors: each block pair (a, b <= a) multiplies its two
/// blocks a stretch at a time, in f64 by faer's matrix product on one thread (dot products a
/// pair at a time left the core waiting on one sum: docs/BENCHMARKS.md, "Clustered PCA's
/// blocked products"). Each block pair is its own sums in a fixed order, so pairs run in
/// parallel and the bytes do not depend on the thread count. A step of `progress` per entry
/// of the lower triangle.
fn products<F>(count: usize, depth: usize, layout: Layout, fill: F, progress: &Progress) -> DMatrix<f64>
where
    F: Fn(Range<usize>, Range<usize>, &mut [f64]) + Sync,
{
    let span = |t: usize| t * BLOCK_VECTORS..((t + 1) * BLOCK_VECTORS).min(count);
    let blocks = count.div_ceil(BLOCK_VECTORS);
    let pairs: Vec<(usize, usize)> = (0..blocks).flat_map(|a| (0..=a).map(move |b| (a, b))).collect();
    let sums: Vec<Mat<f64>> = pairs
        .par_iter()
        .map(|&(a, b)| {
            let (first, second) = (span(a), span(b));
            let mut sum = Mat::zeros(first.len(), second.len());
            let (mut x, mut y) = (vec![], vec![]);
            for start in (0..depth).step_by(BLOCK_DEPTH) {
                let stretch = start..(start + BLOCK_DEPTH).min(depth);
                let values = stretch.len();
                x.resize(first.len() * values, 0.0);
                fill(first.clone(), stretch.clone(), &mut x);
                if a != b {
                    y.resize(second.len() * values, 0.0);
                    fill(second.clone(), stretch, &mut y);
                }
                let right = layout.block(if a == b { &x } else { &y }, values, second.len());
                matmul(sum.as_mut(), layout.block(&x, values, first.len()).transpose(), right, Some(1.0), 1.0, Parallelism::None);
            }
            let (height, width) = (first.len() as u64, second.len() as u64);
            progress.inc(if a == b { height * (height + 1) / 2 } else { height * width });
            sum
        })
        .collect();
    let mut product = DMatrix::zeros(count, count);
    for (&(a, b), sum) in pairs.iter().zip(&sums) {
        // A diagonal block's lower triangle, mirrored: the product is symmetric to the bit.
        for j in 0..sum.ncols() {
            for i in 0..sum.nrows() {
                let (row, column) = (a * BLOCK_VECTORS + i, b * BLOCK_VECTORS + j);
                if column <= row {
                    product[(row, column)] = sum.read(i, j);
                    product[(column, row)] = sum.read(i, j);
                }
            }
        }
    }
    product
}

/// f64 dot product of f32 vectors in four fixed lanes: vectorisable, same bytes every run.
fn dot(a: &[f32], b: &[f32]) -> f64 {
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = a4.remainder().iter().zip(b4.remainder()).map(|(&x, &y)| x as f64 * y as f64).sum();
    let mut lanes = [0.0f64; 4];
    for (x, y) in a4.zip(b4) {
        (0..4).for_each(|k| lanes[k] += x[k] as f64 * y[k] as f64);
    }
    lanes.iter().sum::<f64>() + tail
}

/// (eigenvalue clamped to >= 0, its index), by descending eigenvalue.
fn descending(eigenvalues: &DVector<f64>) -> Vec<(f64, usize)> {
    let mut order: Vec<(f64, usize)> = eigenvalues.iter().enumerate().map(|(i, &v)| (v.max(0.0), i)).collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    order
}

/// PCA of the rows `members` (non-empty) of `data` (row-major, `cols` per row) keeping `basis`
/// vectors, by the Gram matrix route. The weights are projections, so a reconstruction is the
/// orthogonal projection onto the cluster's affine subspace.
pub fn cluster_pca(data: &[f32], cols: usize, members: &[u32], basis: usize) -> ClusterPca {
    let centred = Centred::new(Rows { values: data, cols }, members);
    let by_covariance = cols < members.len();
    let matrix = if by_covariance { centred.covariance() } else { centred.gram() };
    let (eigenvalues, eigenvectors) =
        if basis > 0 && matrix.nrows() > LEADING_ONLY_SIDE { leading_eigenpairs(&matrix, basis) } else { eigen_decomposition(&matrix) };
    let order = descending(&eigenvalues);
    let floor = RANK_TOLERANCE * order[0].0;
    let size = eigenvectors.nrows();
    let eigenvector = |i: usize| &eigenvectors.as_slice()[i * size..][..size];
    // The covariance's eigenvectors are the basis; the Gram matrix's map to it through X^T.
    let vector = |i: usize| if by_covariance { unit(eigenvector(i)) } else { centred.basis_vector(eigenvector(i)) };
    let mut basis_vectors: Vec<Vec<f32>> = order.iter().take(basis).filter(|o| o.0 > floor).map(|&(_, i)| vector(i)).collect();
    basis_vectors.resize(basis, vec![0.0; cols]);
    let mean_dots: Vec<f64> = basis_vectors.iter().map(|b| dot(&centred.mean, b)).collect();
    let weights = (0..members.len())
        .into_par_iter()
        .map(|e| basis_vectors.iter().zip(&mean_dots).map(|(b, &m)| centred.weight(e, b, m)).collect())
        .collect();
    ClusterPca {
        members: members.to_vec(),
        mean: centred.mean,
        eigenvalues: order.iter().map(|o| o.0).collect(),
        basis: basis_vectors,
        weights,
    }
}

fn unit(v: &[f64]) -> Vec<f32> {
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter().map(|x| (x / norm) as f32).collect()
}

/// The centred Gram matrix of the rows `members` from the uncentred one of every row, U:
/// (x_i - m) . (x_j - m) = U_ij - r_i - r_j + s, r_i the mean of U_ik over the members k, s the
/// mean of the r_i.
fn centred(uncentred: &DMatrix<f64>, members: &[u32]) -> DMatrix<f64> {
    let n = members.len();
    let u = |i: usize, j: usize| uncentred[(members[i] as usize, members[j] as usize)];
    let r: Vec<f64> = (0..n).map(|i| (0..n).map(|k| u(i, k)).sum::<f64>() / n as f64).collect();
    let s = r.iter().sum::<f64>() / n as f64;
    DMatrix::from_fn(n, n, |i, j| u(i, j) - r[i] - r[j] + s)
}

/// The descending eigenvalues of `cluster_pca` alone (no eigenvectors: cheaper).
pub fn cluster_eigenvalues(data: &[f32], cols: usize, members: &[u32]) -> Vec<f64> {
    let centred = Centred::new(Rows { values: data, cols }, members);
    let matrix = if cols < members.len() { centred.covariance() } else { centred.gram() };
    descending(&symmetric_eigenvalues(&matrix)).iter().map(|o| o.0).collect()
}

/// Members (ascending) of each of `clusters` clusters.
pub fn groups(assignment: &[u32], clusters: usize) -> Vec<Vec<u32>> {
    let mut members = vec![vec![]; clusters];
    assignment.iter().enumerate().for_each(|(e, &c)| members[c as usize].push(e as u32));
    members
}

/// A clustered PCA of N points: C clusters of D basis vectors each.
#[derive(Clone, Debug, PartialEq)]
pub struct Cpca {
    /// Cluster id per point.
    pub assignment: Vec<u32>,
    pub clusters: Vec<ClusterPca>,
    /// D, the same for every cluster.
    pub basis: usize,
}

/// Fits a clustered PCA of `data` (row-major, `cols` per row) clustered by `features`
/// (`feature_dims` per row) into `clusters` clusters (fewer if the features have fewer distinct
/// points) of `basis` vectors. Refuses malformed or non-finite input, naming the problem.
pub fn fit(data: &[f32], cols: usize, features: &[f32], feature_dims: usize, clusters: usize, basis: usize) -> Result<Cpca, String> {
    validate(data, cols, features, feature_dims, &[clusters])?;
    let tree = divisive_clusters(features, feature_dims, clusters);
    let assignment = tree.assignment(tree.max_clusters());
    Ok(Cpca { clusters: cluster_pcas(data, cols, &groups(&assignment, tree.max_clusters()), basis), assignment, basis })
}

/// `cluster_pca` of each group, the clusters side by side on the worker threads: each one's
/// eigen-decomposition runs on one thread (light clouds on the scale scene refit clusters of
/// a thousand vertices twenty times a zone). Each is computed alone, so the bytes do not depend
/// on the thread count.
fn cluster_pcas(data: &[f32], cols: usize, groups: &[Vec<u32>], basis: usize) -> Vec<ClusterPca> {
    groups.par_iter().map(|m| cluster_pca(data, cols, m, basis)).collect()
}

/// Sloan et al. 2003's refinement of a fitted clustered PCA: every point moves to the cluster
/// whose mean and basis reconstruct it best (ties to the lower cluster), then each cluster's
/// PCA is fitted again, until no point moves or after `iterations` rounds; a cluster left empty
/// is dropped. Each round can only lower the squared error: a point moves only to a cluster
/// that reconstructs it better, and a cluster's new PCA fits its new members at least as well.
/// Returns the refined fit and the rounds taken.
pub fn refine(data: &[f32], cols: usize, fitted: Cpca, iterations: usize) -> (Cpca, usize) {
    let rows = Rows { values: data, cols };
    let mut cpca = fitted;
    for round in 0..iterations {
        let assignment: Vec<u32> = (0..cpca.assignment.len())
            .into_par_iter()
            .map(|e| {
                let error = |c: &ClusterPca| projection_error(rows.row(e), c);
                let current = cpca.assignment[e] as usize;
                let mut best = (error(&cpca.clusters[current]), current);
                for (c, cluster) in cpca.clusters.iter().enumerate() {
                    let candidate = error(cluster);
                    if candidate < best.0 || (candidate == best.0 && c < best.1) {
                        best = (candidate, c);
                    }
                }
                best.1 as u32
            })
            .collect();
        if assignment == cpca.assignment {
            return (cpca, round);
        }
        let groups: Vec<Vec<u32>> = groups(&assignment, cpca.clusters.len()).into_iter().filter(|m| !m.is_empty()).collect();
        let mut renumbered = vec![0u32; assignment.len()];
        for (c, members) in groups.iter().enumerate() {
            members.iter().for_each(|&e| renumbered[e as usize] = c as u32);
        }
        cpca = Cpca { clusters: cluster_pcas(data, cols, &groups, cpca.basis), assignment: renumbered, basis: cpca.basis };
    }
    (cpca, iterations)
}

/// |x - M|^2 - sum_d ((x - M) . B_d)^2: the squared error of the best reconstruction of `x` by
/// the cluster (its basis is orthonormal, or zero vectors).
fn projection_error(x: &[f32], cluster: &ClusterPca) -> f64 {
    let centred: Vec<f32> = x.iter().zip(&cluster.mean).map(|(a, m)| a - m).collect();
    let whole = dot(&centred, &centred);
    cluster.basis.iter().fold(whole, |e, b| e - dot(&centred, b).powi(2)).max(0.0)
}

impl Cpca {
    /// x~_e = M^c + sum_d w^e_d B^c_d for point `row`.
    pub fn reconstruct(&self, row: usize) -> Vec<f32> {
        let cluster = &self.clusters[self.assignment[row] as usize];
        let k = cluster.members.binary_search(&(row as u32)).expect("a point is a member of its cluster");
        let mut x = cluster.mean.clone();
        for (&w, b) in cluster.weights[k].iter().zip(&cluster.basis) {
            x.iter_mut().zip(b).for_each(|(xi, &bi)| *xi += w * bi);
        }
        x
    }

    /// sqrt(sum_e |x_e - x~_e|^2 / sum_e |x_e|^2) over the fitted `data`, by reconstruction.
    pub fn relative_error(&self, data: &[f32]) -> f64 {
        let rows = Rows { values: data, cols: data.len() / self.assignment.len() };
        let per_row: Vec<(f64, f64)> = (0..self.assignment.len())
            .into_par_iter()
            .map(|e| {
                let (x, r) = (rows.row(e), self.reconstruct(e));
                (x.iter().zip(&r).map(|(&a, &b)| (a as f64 - b as f64).powi(2)).sum(), dot(x, x))
            })
            .collect();
        let (error, total) = per_row.iter().fold((0.0, 0.0), |s, r| (s.0 + r.0, s.1 + r.1));
        relative(error, total)
    }
}

fn relative(squared_error: f64, squared_total: f64) -> f64 {
    if squared_total > 0.0 {
        (squared_error / squared_total).sqrt()
    } else {
        0.0
    }
}

/// One (C, D) configuration: its relative error and its size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub clusters: usize,
    pub basis: usize,
    /// sqrt(sum of dropped eigenvalues / sum_e |x_e|^2): what `Cpca::relative_error` measures.
    pub relative_error: f64,
    /// C (1 + D) textures of P values plus N D weights.
    pub stored_values: usize,
}

/// The relative error of every (C, D) with C in `cluster_counts` (those the features allow)
/// and D in 0..=max_basis, from one cluster tree and one eigen-decomposition per distinct
/// cluster, without reconstructing anything. Refuses what [`fit`] refuses.
pub fn error_table(
    data: &[f32],
    cols: usize,
    features: &[f32],
    feature_dims: usize,
    cluster_counts: &[usize],
    max_basis: usize,
) -> Result<Vec<Candidate>, String> {
    validate(data, cols, features, feature_dims, cluster_counts)?;
    let tree = divisive_clusters(features, feature_dims, *cluster_counts.iter().max().unwrap());
    let (rows, total) = (data.len() / cols, dot(data, data));
    let mut eigenvalues: BTreeMap<Vec<u32>, Vec<f64>> = BTreeMap::new();
    let mut table = vec![];
    let counts: Vec<usize> = cluster_counts.iter().copied().filter(|&c| c <= tree.max_clusters()).collect();
    // Fewer rows than values a row: every cluster's centred Gram matrix comes from the rows'
    // one uncentred Gram matrix, made once and reading the rows in place.
    let by_gram = cols >= rows;
    // The search is a long stage of its own on a large scene (minutes): a log sees it move,
    // a step per entry of the Gram matrix and per cluster.
    let steps = if by_gram { rows * (rows + 1) / 2 } else { 0 } + counts.iter().sum::<usize>();
    let mut progress = Progress::new(steps as u64, "clustered PCA's error table", true);
    let all = Rows { values: data, cols };
    let uncentred = by_gram.then(|| all.gram(&(0..rows as u32).collect::<Vec<_>>(), &progress));
    for c in counts {
        let mut dropped = vec![0.0; max_basis + 1];
        for members in groups(&tree.assignment(c), c) {
            let values = eigenvalues.entry(members).or_insert_with_key(|m| match &uncentred {
                Some(u) => descending(&symmetric_eigenvalues(&centred(u, m))).iter().map(|o| o.0).collect(),
                None => cluster_eigenvalues(data, cols, m),
            });
            dropped.iter_mut().enumerate().for_each(|(d, sum)| *sum += values.iter().skip(d).sum::<f64>());
            progress.inc(1);
        }
        table.extend(dropped.iter().enumerate().map(|(d, &squared)| Candidate {
            clusters: c,
            basis: d,
            relative_error: relative(squared, total),
            stored_values: c * (1 + d) * cols + rows * d,
        }));
    }
    progress.finish();
    Ok(table)
}

/// Sloan et al. 2003's variable allocation: `vectors` basis vectors shared out among clusters
/// of these descending eigenvalues, each vector to the cluster whose next eigenvalue is the
/// largest (ties to the lower cluster), at most `most` a cluster, none for an eigenvalue of
/// rounding noise. Each cluster's vectors are a prefix of its eigenvalues, so this drops the
/// least squared error any split of that many vectors can.
pub fn allocate(eigenvalues: &[&[f64]], vectors: usize, most: usize) -> Vec<usize> {
    let mut candidates: Vec<(f64, usize, usize)> = eigenvalues
        .iter()
        .enumerate()
        .flat_map(|(c, values)| {
            let floor = RANK_TOLERANCE * values.first().copied().unwrap_or(0.0);
            values.iter().take(most).enumerate().filter(move |(_, &v)| v > floor && v > 0.0).map(move |(d, &v)| (v, c, d))
        })
        .collect();
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut counts = vec![0; eigenvalues.len()];
    candidates.iter().take(vectors).for_each(|&(_, c, _)| counts[c] += 1);
    counts
}

/// The candidate with the fewest stored values whose relative error is within `budget`, ties
/// going to the smaller error (then the earlier entry); None if none is.
pub fn choose(table: &[Candidate], budget: f64) -> Option<Candidate> {
    table
        .iter()
        .filter(|c| c.relative_error <= budget)
        .copied()
        .min_by(|a, b| a.stored_values.cmp(&b.stored_values).then(a.relative_error.total_cmp(&b.relative_error)))
}

fn validate(data: &[f32], cols: usize, features: &[f32], feature_dims: usize, cluster_counts: &[usize]) -> Result<(), String> {
    if data.is_empty() || cols == 0 {
        return Err("no data: at least one row of at least one value is needed".into());
    }
    if !data.len().is_multiple_of(cols) {
        return Err(format!("data holds {} values, not whole rows of {cols}", data.len()));
    }
    let rows = data.len() / cols;
    if feature_dims == 0 || features.len() != rows * feature_dims {
        return Err(format!("features hold {} values, not {rows} rows of {feature_dims} (>= 1)", features.len()));
    }
    if cluster_counts.is_empty() || cluster_counts.iter().any(|&c| c == 0 || c > rows) {
        return Err(format!("cluster counts {cluster_counts:?} not all in 1..={rows} (the number of rows)"));
    }
    for (values, cols, what) in [(data, cols, "data"), (features, feature_dims, "features")] {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("{what} row {} holds a non-finite value ({})", i / cols, values[i]));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
