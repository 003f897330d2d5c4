//! Tests of the ikd-tree against a brute-force oracle.

use super::*;

#[test]
fn smoke() {
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    let pts: Vec<Point3> = (0..1000).map(|i| Point3::new(i as f32 * 0.1, (i % 7) as f32, 0.0)).collect();
    assert_eq!(t.build(&pts), 1000);
    assert_eq!(t.len(), 1000);
    let nn = t.nearest(&Point3::new(0.0, 0.0, 0.0), 1);
    assert_eq!(nn[0].1, 0.0);
}
