//! Writes that cannot be legal do not compile: a read-only register, a value of the wrong
//! enumeration, a read of a write-only register.

#[test]
fn illegal_register_access_does_not_compile() {
    let t = trybuild::TestCases::new();
    t.compile_fail("compile-fail/*.rs");
}
