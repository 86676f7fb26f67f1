use super::*;

fn array(width: usize, v: &[f64]) -> Rows<f64> {
    Rows::Array(Table::new(width, v.to_vec()).unwrap())
}

#[test]
fn an_array_equals_the_inline_rows_with_the_same_numbers() {
    let inline = Rows::Inline(vec![vec![1.0, 2.0], vec![3.0, f64::NAN]]);
    let a = array(2, &[1.0, 2.0, 3.0, f64::NAN]);
    assert_eq!(a, inline);
    assert_eq!(inline, a);
    assert_eq!(a, a.clone());
    assert_ne!(a, array(2, &[1.0, 2.0, 3.0, 4.0]));
    // Same numbers, other rows.
    assert_ne!(a, array(4, &[1.0, 2.0, 3.0, f64::NAN]));
    assert_ne!(a, Rows::Inline(vec![vec![1.0, 2.0, 3.0, f64::NAN]]));
    assert_ne!(array(2, &[0.0, 1.0]), array(2, &[-0.0, 1.0]));
    assert_eq!(array(3, &[]), Rows::Inline(vec![]));
}

#[test]
fn flat_borrows_an_array_and_locates_a_short_row() {
    let a = array(2, &[1.0, 2.0, 3.0, 4.0]);
    assert!(matches!(
        a.flat(2),
        Ok(Cow::Borrowed(&[1.0, 2.0, 3.0, 4.0]))
    ));
    assert_eq!(a.flat(3), Err((0, 2)));
    let inline = Rows::Inline(vec![vec![1.0, 2.0], vec![3.0]]);
    assert_eq!(inline.flat(2), Err((1, 1)));
    assert_eq!(Rows::<f64>::Inline(vec![]).flat(4).unwrap().len(), 0);
    assert_eq!((a.len(), inline.len()), (2, 2));
}

/// A lent buffer reads its owner's numbers in place and compares as an owned one.
#[test]
fn a_lent_buffer_reads_its_owner_in_place() {
    struct Owner(Box<[f64]>);
    impl AsRef<[f64]> for Owner {
        fn as_ref(&self) -> &[f64] {
            &self.0
        }
    }
    let owner = Owner(vec![1.0, 2.0, 3.0, 4.0].into_boxed_slice());
    let at = owner.0.as_ptr();
    let lent = Shared::lent(owner);
    assert_eq!(lent.as_ptr(), at);
    let copy = lent.clone();
    assert!(Shared::same(&lent, &copy) && copy.as_ptr() == at);
    let owned = Shared::from(vec![1.0, 2.0, 3.0, 4.0]);
    assert!(!Shared::same(&lent, &owned));
    let rows = |v: &Shared<f64>| Rows::Array(Table::new(2, v.clone()).unwrap());
    assert_eq!(rows(&lent), rows(&owned));
    assert_ne!(rows(&lent), array(2, &[1.0, 2.0, 3.0, 5.0]));
    assert_eq!(
        Column::Array(lent),
        Column::Inline(vec![1.0, 2.0, 3.0, 4.0])
    );
}

#[test]
fn tables_refuse_numbers_that_do_not_fill_their_rows() {
    assert!(Table::new(3, vec![1.0; 7]).is_none());
    assert!(Table::new(0, vec![1.0]).is_none());
    assert_eq!(Table::<f64>::new(0, vec![]).unwrap().rows(), 0);
    assert_eq!(Table::new(3, vec![1i64; 6]).unwrap().rows(), 2);
}

#[test]
fn arrays_are_written_as_the_lists_they_equal() {
    #[derive(Serialize, Deserialize)]
    struct Doc {
        rows: Rows<f64>,
        column: Column<i64>,
    }
    let a = array(2, &[1.0, 2.5, 3.0, 4.0]);
    let c = Column::Array(vec![1i64, -2].into());
    let doc = Doc {
        rows: a.clone(),
        column: c.clone(),
    };
    let text = toml::to_string(&doc).unwrap();
    assert_eq!(text, "rows = [[1.0, 2.5], [3.0, 4.0]]\ncolumn = [1, -2]\n");
    let back: Doc = toml::from_str(&text).unwrap();
    assert!(matches!(back.rows, Rows::Inline(_)));
    assert!(matches!(back.column, Column::Inline(_)));
    assert_eq!(back.rows, a);
    assert_eq!(back.column, c);
    assert_eq!(c, Column::Inline(vec![1, -2]));
    assert_ne!(c, Column::Inline(vec![1]));
}
