//! Accesses that cannot be legal do not compile: writing a read-only register, reading a
//! write-only one, writing a value of another register's type. The fixture map is used so the
//! expected compiler output does not change when a shipped map grows.

#[test]
fn illegal_register_access_does_not_compile() {
    let t = trybuild::TestCases::new();
    t.compile_fail("compile-fail/*.rs");
}
