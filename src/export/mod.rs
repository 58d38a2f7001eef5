//! Writing results: OBJ meshes of single frames ([`write_obj`]) and animated binary glTF 2.0
//! files of whole runs ([`gltf`]).

pub mod gltf;
mod obj;

pub use gltf::{glb_bytes, write_glb, GltfMesh, Topology, MAX_GLB_BYTES};
pub use obj::write_obj;
