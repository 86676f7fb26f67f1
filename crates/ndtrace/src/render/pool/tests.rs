use super::*;

#[test]
fn recycled_buffers_come_back_as_they_were_and_in_place() {
    let pool = Pool::new();
    let mut a = pool.take::<f32>(1000);
    assert!(a.iter().all(|&x| x == 0.0));
    a.fill(7.5);
    let ptr = a.as_ptr();
    a.truncate(700);
    pool.recycle(a);
    // The same allocation, for any length from half its capacity up to it: its old values,
    // then zeros past its old length.
    let mut b = pool.take::<f32>(900);
    assert_eq!(b.as_ptr(), ptr);
    assert_eq!(b.len(), 900);
    assert!(b[..700].iter().all(|&x| x == 7.5) && b[700..].iter().all(|&x| x == 0.0));
    b.fill(2.0);
    pool.recycle(b);
    let b = pool.take::<f32>(500);
    assert_eq!((b.as_ptr(), b.len()), (ptr, 500));
    assert!(b.iter().all(|&x| x == 2.0));
    pool.recycle(b);
    // More than twice the length, or too short: a new allocation, zeroed.
    let c = pool.take::<f32>(400);
    assert_ne!(c.as_ptr(), ptr);
    assert!(c.iter().all(|&x| x == 0.0));
    let d = pool.take::<f32>(1001);
    assert_ne!(d.as_ptr(), ptr);
    // Another element type does not take it.
    let e = pool.take::<i32>(1000);
    assert!(e.iter().all(|&x| x == 0));
    assert_eq!(pool.release(), 1000 * 4);
    assert_eq!(pool.release(), 0);
}

#[test]
fn the_pool_is_bounded() {
    let pool = Pool::new();
    for _ in 0..KEEP_BUFFERS + 3 {
        pool.recycle(vec![1i64; 10]);
    }
    assert_eq!(pool.release(), KEEP_BUFFERS * 10 * 8);
    // An empty buffer is not kept, nor one larger than the byte cap.
    pool.recycle(Vec::<f32>::new());
    pool.recycle(Vec::<f32>::with_capacity(KEEP_BYTES / 4 + 1));
    assert_eq!(pool.release(), 0);
    // Nor one that would pass the cap.
    pool.recycle(Vec::<f32>::with_capacity(KEEP_BYTES / 8));
    pool.recycle(Vec::<i32>::with_capacity(KEEP_BYTES / 8));
    pool.recycle(Vec::<i64>::with_capacity(KEEP_BYTES / 16 + 1));
    assert_eq!(pool.release(), KEEP_BYTES);
}
