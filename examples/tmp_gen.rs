fn main() {
    let path = std::env::args().nth(1).unwrap();
    let loaded = embedyn::load(path.as_ref()).unwrap();
    let t = std::time::Instant::now();
    let toks = embedyn::codegen::generate_tokens(&loaded, &Default::default()).unwrap();
    let text = embedyn::codegen::format_tokens(&toks).unwrap();
    eprintln!("generated {} bytes, {} lines in {:?}", text.len(), text.lines().count(), t.elapsed());
    println!("{text}");
}
