// A device named as the model (an endless stream) is refused before it is read: once the macro read
// `/dev/zero` until the compiler ran out of memory.
mod robot {
    embedyn::robot!("/dev/zero");
}
fn main() {}
