//! What a shader's SPIR-V declares (rspirv-reflect): its bindings, the size of its push block
//! and a compute shader's workgroup size. A pipeline is made only for shaders whose
//! declarations agree with what its pass binds and pushes: a disagreement is an error naming
//! the pass and the binding at creation, not a validation message (or garbage) at draw time.

use super::{VkError, VkResult};
use ash::vk;
use std::collections::BTreeMap;

/// One stage's declarations.
pub(super) struct Interface {
    /// Set 0's bindings by number (relume's passes bind one set).
    bindings: BTreeMap<u32, vk::DescriptorType>,
    /// The push block's size in bytes (0 without one).
    push_bytes: u32,
    /// A compute shader's local size.
    pub local_size: Option<[u32; 3]>,
}

/// Reads `spirv`'s declarations; refused, naming `pass`: SPIR-V that does not parse, and a
/// descriptor set other than 0.
pub(super) fn reflect(pass: &str, spirv: &[u8]) -> VkResult<Interface> {
    // rspirv-reflect asserts on some malformed modules; a caller's shader is refused instead.
    std::panic::catch_unwind(|| read(pass, spirv))
        .unwrap_or_else(|_| Err(VkError::Invalid(format!("pass {pass}: its SPIR-V cannot be reflected (malformed)"))))
}

fn read(pass: &str, spirv: &[u8]) -> VkResult<Interface> {
    let fail = |e: rspirv_reflect::ReflectError| VkError::Invalid(format!("pass {pass}: its SPIR-V cannot be reflected: {e}"));
    let reflection = rspirv_reflect::Reflection::new_from_spirv(spirv).map_err(fail)?;
    let mut bindings = BTreeMap::new();
    for (set, declared) in reflection.get_descriptor_sets().map_err(fail)? {
        if set != 0 {
            return Err(VkError::Invalid(format!(
                "pass {pass}: its shader declares descriptor set {set}; relume's passes bind set 0 alone"
            )));
        }
        bindings.extend(declared.into_iter().map(|(binding, info)| (binding, vk::DescriptorType::from_raw(info.ty.0 as i32))));
    }
    let push_bytes = reflection.get_push_constant_range().map_err(fail)?.map_or(0, |p| p.offset + p.size);
    let local_size = reflection.get_compute_group_size().map(|(x, y, z)| [x, y, z]);
    Ok(Interface { bindings, push_bytes, local_size })
}

/// A compute shader's workgroup size, as its SPIR-V declares it ([1, 1, 1] for another stage):
/// for a limit checked before the pass is made.
pub fn workgroup_size(pass: &str, spirv: &[u8]) -> VkResult<[u32; 3]> {
    Ok(reflect(pass, spirv)?.local_size.unwrap_or([1; 3]))
}

/// Refuses, naming `pass` and the binding, a pass whose descriptor set (binding i of kind
/// `kinds[i]`) or push block (`push_bytes`) disagrees with what any of its `stages` declares:
/// another kind or nothing where a stage binds, fewer bytes than a stage's push block (it would
/// read past them) or more than the block padded to 16 (another struct), a push block no stage
/// declares. A binding no stage declares is allowed (a stand-in the variant never reads).
pub(super) fn check(pass: &str, stages: &[&Interface], kinds: &[vk::DescriptorType], push_bytes: u32) -> VkResult<()> {
    if push_bytes > 0 && stages.iter().all(|stage| stage.push_bytes == 0) {
        return Err(VkError::Invalid(format!(
            "pass {pass}: it pushes {push_bytes} bytes, but no stage of its shaders declares a push block"
        )));
    }
    for stage in stages {
        for (&binding, &declared) in &stage.bindings {
            let bound = kinds.get(binding as usize);
            if bound != Some(&declared) {
                let bound = bound.map_or("nothing".to_string(), |kind| format!("a {kind:?}"));
                return Err(VkError::Invalid(format!(
                    "pass {pass}: binding {binding} is a {declared:?} in its shader, but the pass binds {bound} there"
                )));
            }
        }
        if stage.push_bytes != 0 && (push_bytes < stage.push_bytes || push_bytes > stage.push_bytes.next_multiple_of(16)) {
            return Err(VkError::Invalid(format!(
                "pass {pass}: its shader's push block is {} bytes, but the pass pushes {push_bytes}",
                stage.push_bytes
            )));
        }
    }
    Ok(())
}
