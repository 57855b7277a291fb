//! Compiles every `shaders/*.comp` to SPIR-V (Vulkan 1.2 / SPIR-V 1.5) with glslang at build
//! time; a compile error fails the build with glslang's message. `#include "name.glsl"` lines
//! are replaced by that file from `shaders/` (one level, each file once).

use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderSource, ShaderStage, SpirvVersion, Target,
    VulkanVersion,
};
use std::path::PathBuf;

fn main() {
    let shaders = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    println!("cargo:rerun-if-changed={}", shaders.display());
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let compiler = Compiler::acquire().expect("glslang initialises once per process");
    let options = CompilerOptions {
        target: Target::Vulkan {
            version: VulkanVersion::Vulkan1_2,
            spirv_version: SpirvVersion::SPIRV1_5,
        },
        ..Default::default()
    };
    let mut entries: Vec<_> = std::fs::read_dir(&shaders)
        .expect("shaders/ exists")
        .map(|e| e.expect("readable").path())
        .collect();
    entries.sort();
    for path in entries
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "comp"))
    {
        println!("cargo:rerun-if-changed={}", path.display());
        let text = expand_includes(
            &shaders,
            &std::fs::read_to_string(&path).expect("shader is UTF-8"),
        );
        let source = ShaderSource::from(text);
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        // Modules compiled again with a macro defined, as `<name>.<macro>.spv`: code that needs
        // a device feature (float atomics) lives in its own module.
        let extra: &[&str] = if name == "trace.comp" {
            &["SAMPLE_SLICES"]
        } else {
            &[]
        };
        for define in std::iter::once(None).chain(extra.iter().map(|d| Some(*d))) {
            let defines: Vec<(&str, Option<&str>)> =
                define.iter().map(|d| (*d, Some("1"))).collect();
            let spirv = ShaderInput::new(
                &source,
                ShaderStage::Compute,
                &options,
                Some(&defines[..]),
                None,
            )
            .and_then(|input| glslang::Shader::new(compiler, input).parse())
            .and_then(|shader| shader.compile())
            .unwrap_or_else(|e| panic!("shader {name} ({define:?}) does not compile:\n{e}"));
            let bytes: Vec<u8> = spirv.iter().flat_map(|w| w.to_le_bytes()).collect();
            let file = match define {
                None => format!("{name}.spv"),
                Some(d) => format!("{name}.{d}.spv"),
            };
            std::fs::write(out.join(file), bytes).expect("OUT_DIR is writable");
        }
    }
}

fn expand_includes(dir: &std::path::Path, text: &str) -> String {
    text.lines()
        .map(|line| {
            match line
                .trim()
                .strip_prefix("#include \"")
                .and_then(|r| r.strip_suffix('"'))
            {
                Some(name) => {
                    let file = dir.join(name);
                    println!("cargo:rerun-if-changed={}", file.display());
                    std::fs::read_to_string(&file)
                        .unwrap_or_else(|e| panic!("#include {name}: {e}"))
                }
                None => line.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}
