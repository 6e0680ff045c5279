// Shadow rays (any hit, each with its own t_max) through TinyBVH's own
// occlusion functions (traverse_bvh2.cl, traverse_bvh4.cl, traverse_cwbvh.cl),
// for peer_rays_gpu.cpp: batch kernels like TinyBVH's batch_* kernels, which
// trace closest hits with t_max 1e30 only. The ray's t_max is in O.w; hit.x
// becomes 1 when occluded, else 0. Built from the peer's folder, where
// traverse.cl and its includes are.
#include "traverse.cl"

void kernel occluded_ailalaine( const global struct BVHNode* bvhNode, const global uint* idx, const global float4* verts, global struct Ray* rayData, const uint count )
{
	const uint i = get_global_id( 0 );
	if (i >= count) return;
	const float4 O = rayData[i].O;
	const bool hit = isoccluded_ailalaine( bvhNode, idx, verts, 0, O.xyz, rayData[i].D.xyz, rayData[i].rD.xyz, O.w );
	rayData[i].hit = (float4)( hit ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f );
}

void kernel occluded_gpu4way( const global float4* alt4Node, global struct Ray* rayData, const uint count )
{
	const uint i = get_global_id( 0 );
	if (i >= count) return;
	const float4 O = rayData[i].O;
	const bool hit = isoccluded_gpu4way( alt4Node, O.xyz, rayData[i].D.xyz, rayData[i].rD.xyz, O.w );
	rayData[i].hit = (float4)( hit ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f );
}

void kernel occluded_cwbvh( global const float4* cwbvhNodes, global const float4* cwbvhTris, global struct Ray* rayData, const uint count )
{
	const uint i = get_global_id( 0 );
	if (i >= count) return;
	const float tmax = rayData[i].O.w;
#ifdef SIMD_AABBTEST
	float4 O4 = rayData[i].O; O4.w = 1;
	float4 D4 = rayData[i].D; D4.w = 0;
	float4 rD4 = rayData[i].rD; rD4.w = 1;
	const bool hit = isoccluded_cwbvh( cwbvhNodes, cwbvhTris, O4, D4, rD4, tmax );
#else
	const bool hit = isoccluded_cwbvh( cwbvhNodes, cwbvhTris, rayData[i].O.xyz, rayData[i].D.xyz, rayData[i].rD.xyz, tmax );
#endif
	rayData[i].hit = (float4)( hit ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f );
}
