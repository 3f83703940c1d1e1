//! What a compiled kernel declares as its inputs, read from the SPIR-V words (for tests): every
//! uniform, storage and push-constant block with its descriptor set, binding, members, member
//! offsets and whether the kernel may write it, and every texel buffer with its set and binding. A few instructions suffice; see the SPIR-V
//! specification, section 2.3 (physical layout) and 3 (the enumerants used here).

use std::collections::HashMap;

const MAGIC: u32 = 0x0723_0203;
const HEADER_WORDS: usize = 5;

// Opcodes.
const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_ACCELERATION_STRUCTURE: u32 = 5341;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;

// Decorations.
const ARRAY_STRIDE: u32 = 6;
const NON_WRITABLE: u32 = 24;
const BINDING: u32 = 33;
const DESCRIPTOR_SET: u32 = 34;
const OFFSET: u32 = 35;

// An image's dimensionality: a texel buffer.
const DIM_BUFFER: u32 = 5;
// The storage class of opaque handles (images, samplers).
const UNIFORM_CONSTANT: u32 = 0;

/// Storage classes of the blocks a kernel takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StorageClass {
    Uniform,
    PushConstant,
    StorageBuffer,
}

impl StorageClass {
    fn from_word(word: u32) -> Option<Self> {
        match word {
            2 => Some(StorageClass::Uniform),
            9 => Some(StorageClass::PushConstant),
            12 => Some(StorageClass::StorageBuffer),
            _ => None,
        }
    }
}

/// One member of a block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    pub name: String,
    pub offset: Option<u32>,
    /// Bytes from one element to the next, for an array.
    pub array_stride: Option<u32>,
    pub non_writable: bool,
}

/// One block variable of the kernel.
#[derive(Clone, Debug)]
pub struct BlockVariable {
    /// The instance name (empty for a block declared without one).
    pub name: String,
    /// The block's type name.
    pub block: String,
    pub storage_class: StorageClass,
    pub set: Option<u32>,
    pub binding: Option<u32>,
    pub members: Vec<Member>,
}

impl BlockVariable {
    /// Whether the kernel may not write any member (GLSL `readonly`).
    pub fn is_readonly(&self) -> bool {
        self.members.iter().all(|m| m.non_writable)
    }
}

/// A string operand: UTF-8, NUL-terminated, packed little-endian into words.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
    String::from_utf8(bytes).expect("SPIR-V strings are UTF-8")
}

/// The instructions of `spirv` after its header: each one's opcode and operands.
fn instructions(spirv: &[u32]) -> impl Iterator<Item = (u32, &[u32])> {
    assert_eq!(spirv.first(), Some(&MAGIC), "not SPIR-V");
    let mut at = HEADER_WORDS;
    std::iter::from_fn(move || {
        let word = *spirv.get(at)?;
        let count = (word >> 16) as usize;
        assert!(count > 0 && at + count <= spirv.len(), "malformed instruction at word {at}");
        let operands = &spirv[at + 1..at + count];
        at += count;
        Some((word & 0xffff, operands))
    })
}

/// Every uniform, push-constant and storage block variable of `spirv`.
pub fn block_variables(spirv: &[u32]) -> Vec<BlockVariable> {
    let mut names = HashMap::new();
    let mut member_names = HashMap::new();
    let mut member_types = HashMap::new();
    let mut pointees = HashMap::new();
    let mut decorations: HashMap<(u32, u32), u32> = HashMap::new();
    let mut member_decorations: HashMap<(u32, u32, u32), u32> = HashMap::new();
    let mut variables = Vec::new();
    for (opcode, operands) in instructions(spirv) {
        match opcode {
            OP_NAME => {
                names.insert(operands[0], string(&operands[1..]));
            }
            OP_MEMBER_NAME => {
                member_names.insert((operands[0], operands[1]), string(&operands[2..]));
            }
            OP_TYPE_STRUCT => {
                member_types.insert(operands[0], operands[1..].to_vec());
            }
            OP_TYPE_POINTER => {
                pointees.insert(operands[0], operands[2]);
            }
            OP_VARIABLE => {
                if let Some(class) = StorageClass::from_word(operands[2]) {
                    variables.push((operands[0], operands[1], class));
                }
            }
            OP_DECORATE => {
                decorations.insert((operands[0], operands[1]), operands.get(2).copied().unwrap_or(0));
            }
            OP_MEMBER_DECORATE => {
                member_decorations
                    .insert((operands[0], operands[1], operands[2]), operands.get(3).copied().unwrap_or(0));
            }
            _ => {}
        }
    }
    variables
        .into_iter()
        .map(|(pointer, id, storage_class)| {
            let block = pointees[&pointer];
            let members = member_types[&block]
                .iter()
                .zip(0..)
                .map(|(ty, m)| Member {
                    name: member_names.get(&(block, m)).cloned().unwrap_or_default(),
                    offset: member_decorations.get(&(block, m, OFFSET)).copied(),
                    array_stride: decorations.get(&(*ty, ARRAY_STRIDE)).copied(),
                    non_writable: member_decorations.contains_key(&(block, m, NON_WRITABLE)),
                })
                .collect();
            BlockVariable {
                name: names.get(&id).cloned().unwrap_or_default(),
                block: names.get(&block).cloned().unwrap_or_default(),
                storage_class,
                set: decorations.get(&(id, DESCRIPTOR_SET)).copied(),
                binding: decorations.get(&(id, BINDING)).copied(),
                members,
            }
        })
        .collect()
}

/// One uniform texel buffer of the kernel: GLSL `textureBuffer` (read by `texelFetch` with
/// GL_EXT_samplerless_texture_functions) or `samplerBuffer`, of any component type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TexelBufferVariable {
    pub name: String,
    pub set: Option<u32>,
    pub binding: Option<u32>,
}

/// Every uniform texel buffer of `spirv` (not the storage texel buffers of `imageBuffer`).
pub fn texel_buffer_variables(spirv: &[u32]) -> Vec<TexelBufferVariable> {
    let mut buffer_images = Vec::new();
    uniform_constant_variables(spirv, |opcode, operands| match opcode {
        // Result, sampled type, Dim, Depth, Arrayed, MS, Sampled (1: read without a sampler's
        // help, as a uniform texel buffer; 2: a storage image), ...
        OP_TYPE_IMAGE if operands[2] == DIM_BUFFER && operands[6] == 1 => {
            buffer_images.push(operands[0]);
            Some(operands[0])
        }
        OP_TYPE_SAMPLED_IMAGE if buffer_images.contains(&operands[1]) => Some(operands[0]),
        _ => None,
    })
}

/// Every acceleration structure the module declares (`uniform accelerationStructureEXT`), with its
/// name, set and binding (a [`TexelBufferVariable`] names the same three).
pub fn acceleration_structure_variables(spirv: &[u32]) -> Vec<TexelBufferVariable> {
    uniform_constant_variables(spirv, |opcode, operands| {
        (opcode == OP_TYPE_ACCELERATION_STRUCTURE).then(|| operands[0])
    })
}

/// The variables of UniformConstant pointers to the types `pointee` picks out, with their names,
/// sets and bindings. `pointee` sees every instruction in order and returns the id of a type it
/// declares that counts (it may keep state: a sampled image counts when its image does).
fn uniform_constant_variables(
    spirv: &[u32],
    mut pointee: impl FnMut(u32, &[u32]) -> Option<u32>,
) -> Vec<TexelBufferVariable> {
    let (mut names, mut decorations) = (HashMap::new(), HashMap::new());
    let (mut types, mut pointers, mut variables) = (Vec::new(), Vec::new(), Vec::new());
    for (opcode, operands) in instructions(spirv) {
        if let Some(id) = pointee(opcode, operands) {
            types.push(id);
            continue;
        }
        match opcode {
            OP_NAME => {
                names.insert(operands[0], string(&operands[1..]));
            }
            OP_TYPE_POINTER if operands[1] == UNIFORM_CONSTANT && types.contains(&operands[2]) => {
                pointers.push(operands[0])
            }
            OP_VARIABLE if pointers.contains(&operands[0]) => variables.push(operands[1]),
            OP_DECORATE => {
                decorations.insert((operands[0], operands[1]), operands.get(2).copied().unwrap_or(0));
            }
            _ => {}
        }
    }
    variables
        .into_iter()
        .map(|id| TexelBufferVariable {
            name: names.get(&id).cloned().unwrap_or_default(),
            set: decorations.get(&(id, DESCRIPTOR_SET)).copied(),
            binding: decorations.get(&(id, BINDING)).copied(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::compile_compute;

    #[test]
    fn reads_bindings_offsets_and_access_of_a_small_kernel() {
        let spirv = compile_compute(
            "#version 460\nlayout(local_size_x = 1) in;\n\
             layout(std140, set = 0, binding = 3) uniform Params { vec3 v; float f; } params;\n\
             layout(std430, set = 0, binding = 5) readonly buffer Input { uint values[]; };\n\
             layout(std430, set = 0, binding = 6) buffer Output { uint out_values[]; };\n\
             layout(push_constant) uniform Push { uint n; } push;\n\
             void main() { out_values[0] = values[push.n] + uint(params.f); }\n",
        )
        .unwrap();
        let vars = block_variables(&spirv);
        let find =
            |block: &str| vars.iter().find(|v| v.block == block).unwrap_or_else(|| panic!("{block} in {vars:?}"));
        let params = find("Params");
        assert_eq!(
            (params.name.as_str(), params.storage_class, params.set, params.binding),
            ("params", StorageClass::Uniform, Some(0), Some(3))
        );
        let offsets: Vec<_> = params.members.iter().map(|m| (m.name.as_str(), m.offset)).collect();
        assert_eq!(offsets, [("v", Some(0)), ("f", Some(12))]);
        let input = find("Input");
        assert_eq!(
            (input.storage_class, input.binding, input.members[0].name.as_str(), input.is_readonly()),
            (StorageClass::StorageBuffer, Some(5), "values", true)
        );
        assert_eq!(input.members[0].array_stride, Some(4));
        assert!(!find("Output").is_readonly());
        assert_eq!((find("Push").storage_class, find("Push").binding), (StorageClass::PushConstant, None));
    }

    #[test]
    fn reads_the_texel_buffers_of_a_small_kernel() {
        let spirv = compile_compute(
            "#version 460\n#extension GL_EXT_samplerless_texture_functions : require\nlayout(local_size_x = 1) in;\n\
             layout(set = 0, binding = 2) uniform utextureBuffer records;\n\
             layout(set = 0, binding = 4) uniform sampler2D picture;\n\
             layout(std430, set = 0, binding = 6) buffer Output { uvec4 out_values[]; };\n\
             void main() { out_values[0] = texelFetch(records, 3) + uvec4(texelFetch(picture, ivec2(0), 0)); }\n",
        )
        .unwrap();
        assert_eq!(
            texel_buffer_variables(&spirv),
            [TexelBufferVariable { name: "records".into(), set: Some(0), binding: Some(2) }]
        );
        assert!(block_variables(&spirv).iter().all(|v| v.binding == Some(6)), "a texel buffer or image is no block");
    }
}
