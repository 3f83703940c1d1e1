//! Host structs whose GLSL block is written from their own field list, so that the two cannot
//! drift: [`glsl_block!`] declares the `#[repr(C)]` struct and, from the same tokens, the list of
//! its members with their GLSL types and byte offsets. Each field's doc comment becomes the
//! member's comment in the generated GLSL. bindings.rs declares the blocks with these members; its
//! tests read the compiled kernel's member offsets back and compare them with the host's.

use crate::gpu::TexelWords;

/// A host type with a GLSL twin of the same bytes: a scalar or vector, or a struct of
/// shaders/layout.glsl.
pub trait GlslType: bytemuck::Pod {
    /// The type's name in GLSL.
    const NAME: &'static str;
    /// What follows a member's name in GLSL: `[3]` for an array of three, else nothing.
    const ARRAY: &'static str = "";
}

/// The rows of a 3x4 affine map (an instance's transforms).
impl GlslType for [[f32; 4]; 3] {
    const NAME: &'static str = "vec4";
    const ARRAY: &'static str = "[3]";
}

macro_rules! glsl_names {
    ($($host:ty => $glsl:literal),* $(,)?) => {
        $(impl GlslType for $host {
            const NAME: &'static str = $glsl;
        })*
    };
}

glsl_names! {
    f32 => "float",
    u32 => "uint",
    [f32; 2] => "vec2",
    [f32; 3] => "vec3",
    [f32; 4] => "vec4",
    [u32; 2] => "uvec2",
    [u32; 3] => "uvec3",
    [u32; 4] => "uvec4",
}

/// What one member of a record read through a texel buffer holds: a `vec4` or `vec2` (the texel's
/// bits reinterpreted), a `uvec4`, a `float` or a `uint`, each one texel; or an array of `n`
/// `vec4`s (a matrix's rows), `n` texels. A texel is as wide as its member, so that a record of
/// single words (a CDF, packed normals) is read word by word rather than padded to 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texel {
    Vec4,
    Uvec4,
    Vec2,
    Float,
    Uint,
    Vec4Array(usize),
}

impl Texel {
    /// How many texels the member takes.
    pub const fn count(self) -> usize {
        match self {
            Texel::Vec4Array(n) => n,
            _ => 1,
        }
    }

    /// The record's size in texels: its members' counts added up.
    pub const fn record_texels(members: &[Texel]) -> usize {
        let mut total = 0;
        let mut k = 0;
        while k < members.len() {
            total += members[k].count();
            k += 1;
        }
        total
    }

    /// How many 32-bit words the texel holds.
    pub const fn words(self) -> TexelWords {
        match self {
            Texel::Vec4 | Texel::Uvec4 | Texel::Vec4Array(_) => TexelWords::Four,
            Texel::Vec2 => TexelWords::Two,
            Texel::Float | Texel::Uint => TexelWords::One,
        }
    }
}

/// A host record the kernel reads as consecutive texels of a texel buffer (bindings.rs,
/// `Shape::TexelBuffer`), all as wide: its GLSL type's members, of these kinds in order (a scalar
/// or vector record is its one texel).
pub trait GlslTexels: GlslType {
    const TEXELS: &'static [Texel];
}

impl GlslTexels for f32 {
    const TEXELS: &'static [Texel] = &[Texel::Float];
}
impl GlslTexels for u32 {
    const TEXELS: &'static [Texel] = &[Texel::Uint];
}
impl GlslTexels for [f32; 2] {
    const TEXELS: &'static [Texel] = &[Texel::Vec2];
}
impl GlslTexels for [f32; 4] {
    const TEXELS: &'static [Texel] = &[Texel::Vec4];
}

/// One member of a block: name, GLSL type, byte offset in the host struct, and the doc comment.
#[derive(Clone, Copy, Debug)]
pub struct GlslMember {
    pub name: &'static str,
    pub glsl_type: &'static str,
    /// `[n]` after the name of an array member, else empty.
    pub array: &'static str,
    pub offset: usize,
    pub doc: &'static [&'static str],
}

/// A host struct that the kernel sees as a uniform, push-constant or storage block, or as the
/// element of an array (a record of layout.rs).
pub trait GlslBlock: bytemuck::Pod {
    /// The block's type name in GLSL (the host struct's name unless declared `as "Name"`).
    const NAME: &'static str;
    /// The struct's doc comment, a line an entry.
    const DOC: &'static [&'static str];
    /// Every field, in declaration order.
    const MEMBERS: &'static [GlslMember];
}

/// `members` as GLSL block members, one a line, each after its doc comment.
pub fn glsl_members(members: &[GlslMember]) -> String {
    let mut out = String::new();
    for member in members {
        for line in member.doc {
            out += &format!("    //{line}\n");
        }
        out += &format!("    {} {}{};\n", member.glsl_type, member.name, member.array);
    }
    out
}

/// `struct NAME { ... };` for a record, after its doc comment: what the kernel declares it as.
pub fn glsl_struct<T: GlslBlock>() -> String {
    let mut out = String::new();
    for line in T::DOC {
        out += &format!("//{line}\n");
    }
    out + &format!("struct {} {{\n{}}};\n", T::NAME, glsl_members(T::MEMBERS))
}

/// Declares a `#[repr(C)]`, `Pod` struct whose fields are all [`GlslType`]s, and its
/// [`GlslBlock`] member list, under the struct's own name or the GLSL name given after `as`.
/// Fields take doc comments only (they are copied into the GLSL).
macro_rules! glsl_block {
    (
        $(#[doc = $struct_doc:literal])*
        pub struct $name:ident $(as $glsl_name:literal)? {
            $($(#[doc = $doc:literal])* pub $field:ident: $ty:ty,)*
        }
    ) => {
        $(#[doc = $struct_doc])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, PartialEq, ::bytemuck::Pod, ::bytemuck::Zeroable)]
        pub struct $name {
            $($(#[doc = $doc])* pub $field: $ty,)*
        }

        impl $crate::render::glsl_block::GlslBlock for $name {
            // The name after `as` where there is one, else the struct's.
            const NAME: &'static str = [$($glsl_name,)? stringify!($name)][0];
            const DOC: &'static [&'static str] = &[$($struct_doc),*];
            const MEMBERS: &'static [$crate::render::glsl_block::GlslMember] = &[$(
                $crate::render::glsl_block::GlslMember {
                    name: stringify!($field),
                    glsl_type: <$ty as $crate::render::glsl_block::GlslType>::NAME,
                    array: <$ty as $crate::render::glsl_block::GlslType>::ARRAY,
                    offset: ::std::mem::offset_of!($name, $field),
                    doc: &[$($doc),*],
                },
            )*];
        }
    };
}
pub(crate) use glsl_block;

#[cfg(test)]
mod tests {
    use super::*;

    glsl_block! {
        /// A block of every shape of member.
        pub struct Example {
            /// Where it is.
            pub position: [f32; 3],
            pub count: u32,
        }
    }

    #[test]
    fn members_carry_their_glsl_type_offset_and_comment() {
        let m = Example::MEMBERS;
        assert_eq!(Example::NAME, "Example");
        assert_eq!((m[0].name, m[0].glsl_type, m[0].offset), ("position", "vec3", 0));
        assert_eq!((m[1].name, m[1].glsl_type, m[1].offset), ("count", "uint", 12));
        assert_eq!(glsl_members(m), "    // Where it is.\n    vec3 position;\n    uint count;\n");
    }
}
