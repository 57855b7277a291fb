//! Value parsers shared by the subcommands' arguments.

use glam::IVec3;

/// A window size, WxH, each 64..=16384.
pub(crate) fn window_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{s:?} is not WxH"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (64..=16384).contains(n))
            .ok_or_else(|| format!("{v:?} is not a size in 64..=16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

/// An image or internal resolution, WxH, each 1..=8192.
pub(crate) fn resolution(s: &str) -> Result<(u32, u32), String> {
    match s
        .split_once('x')
        .map(|(w, h)| (w.trim().parse::<u32>(), h.trim().parse::<u32>()))
    {
        Some((Ok(w), Ok(h))) if (1..=8192).contains(&w) && (1..=8192).contains(&h) => Ok((w, h)),
        _ => Err(format!("{s:?}: expected WxH, each 1..=8192")),
    }
}

/// The integers of `s` between `sep`s.
fn ints(s: &str, sep: char) -> Result<Vec<i32>, String> {
    s.split(sep)
        .map(|p| p.trim().parse::<i32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))
}

/// An integer offset, X,Y,Z.
pub(crate) fn ivec3(s: &str) -> Result<IVec3, String> {
    match ints(s, ',')?[..] {
        [x, y, z] => Ok(IVec3::new(x, y, z)),
        _ => Err(format!("{s:?}: expected three integers X,Y,Z")),
    }
}

/// A grid size in voxels, WxHxD, each positive.
pub(crate) fn grid_size(s: &str) -> Result<IVec3, String> {
    match ints(s, 'x')?[..] {
        [x, y, z] if x > 0 && y > 0 && z > 0 => Ok(IVec3::new(x, y, z)),
        _ => Err(format!("{s:?}: expected three positive integers WxHxD")),
    }
}

/// A sample sequence's name: sobol or independent.
pub(crate) fn sequence(s: &str) -> Result<::render::Sequence, String> {
    match s {
        "sobol" => Ok(::render::Sequence::Sobol),
        "independent" => Ok(::render::Sequence::Independent),
        _ => Err(format!("{s:?} is not a sequence (sobol or independent)")),
    }
}

/// A noise function's name: perlin, open-simplex, super-simplex or value.
pub(crate) fn noise(s: &str) -> Result<brickmap::terrain::NoiseKind, String> {
    use brickmap::terrain::NoiseKind;
    match s {
        "perlin" => Ok(NoiseKind::Perlin),
        "open-simplex" => Ok(NoiseKind::OpenSimplex),
        "super-simplex" => Ok(NoiseKind::SuperSimplex),
        "value" => Ok(NoiseKind::Value),
        _ => Err(format!(
            "{s:?} is not a noise function (perlin, open-simplex, super-simplex or value)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_offsets_parse_or_say_what_is_wrong() {
        assert_eq!(resolution("32x18"), Ok((32, 18)));
        assert!(resolution("0x5").unwrap_err().contains("1..=8192"));
        assert_eq!(window_size("960x540"), Ok((960, 540)));
        assert!(window_size("32x540").is_err());
        assert_eq!(ivec3("1,-2,3"), Ok(IVec3::new(1, -2, 3)));
        assert!(ivec3("1,2").unwrap_err().contains("X,Y,Z"));
        assert_eq!(grid_size("48x24x48"), Ok(IVec3::new(48, 24, 48)));
        assert!(grid_size("48x0x48").is_err());
        assert_eq!(sequence("sobol"), Ok(::render::Sequence::Sobol));
        assert!(sequence("halton").is_err());
        assert_eq!(
            noise("open-simplex"),
            Ok(brickmap::terrain::NoiseKind::OpenSimplex)
        );
        assert!(noise("simplex").unwrap_err().contains("perlin"));
    }
}
