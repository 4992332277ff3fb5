//! The trajectory CSV of `urdyn simulate` read back: header and numeric rows.

/// (column names, rows) of a CSV written by `simulate --out`.
pub fn read_csv(p: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}
