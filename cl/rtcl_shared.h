/* Everything that crosses the host/device boundary, written once and included
 * both by the C host and by OpenCL C (docs/STYLE.md rule 2).
 *
 * The device scene is one contiguous block: a struct rt_scene header, then the
 * material, sphere, plane, light, triangle and vertex arrays at the
 * byte offsets the header gives. Every struct is a whole number of 16-byte units so that the block
 * can be copied into __local memory as uint4 words. Vectors are float4 on both sides (cl_float4 on
 * the host) with w unused, except where a scalar shares the 16-byte load of the vector beside it: a
 * sphere's centre carries radius² (one load feeds the sphere test), a plane's normal its offset, a
 * triangle's vertex indices its material and whether it is smooth, a
 * material's colour ka, a queued ray's origin its weight, and the camera
 * vectors the half-extents and epsilon. Fields of their own would cost the
 * walk extra loads (tried: four more scalar loads in each walk kernel's NVPTX
 * code from clang, where the w lanes come with 16-byte loads made anyway). The
 * kernels read those lanes only through named accessors: the ones at the end
 * of this file, and for the scene header, which lives in __local or
 * __global memory as the host decides, scene_epsilon, scene_half_width and
 * scene_half_height in cl/tracer.cl.
 */
#ifndef RTCL_SHARED_H
#define RTCL_SHARED_H

#ifdef __OPENCL_VERSION__
typedef float4 rt_vec4;
typedef float rt_float;
typedef int rt_int;
typedef uint rt_uint;
typedef uint4 rt_uvec4;
#else
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl_platform.h>
typedef cl_float4 rt_vec4;
typedef cl_float rt_float;
typedef cl_int rt_int;
typedef cl_uint rt_uint;
typedef cl_uint4 rt_uvec4;
#endif

struct rt_material {
	rt_vec4 color;	    /* C; w: ka, loaded with the colour it scales
			       (material_ambient) */
	rt_float diffuse;   /* kd */
	rt_float specular;  /* ks */
	rt_float shininess; /* Blinn-Phong exponent */
	rt_float reflect;   /* kr */
	rt_float transmit;  /* kt */
	rt_float ior;
	rt_float inv_ior; /* 1/ior, the eta of a ray entering the object */
	rt_int fresnel;	  /* RT_FRESNEL_*: read only in programs built with
			     RTCL_FRESNEL (RENDERING.md, "Fresnel") */
};

/* A material's Fresnel term (SCENE.md's "fresnel"). */
#define RT_FRESNEL_OFF 0
#define RT_FRESNEL_DIELECTRIC 1
#define RT_FRESNEL_CONDUCTOR 2

/* The tracer tests spheres this many at a time. */
#define RT_SPHERE_GROUP 4

struct rt_sphere {
	rt_vec4 center; /* w: radius², so that one 16-byte load feeds a test
			   (sphere_radius2); -1 in the padding, which
			   nothing hits */
	rt_float radius;
	rt_float inv_radius; /* 1/radius */
	rt_int material;
	rt_int scene_index; /* its index in the scene: with a BVH the spheres are
			       in leaf order (host/layout/scene_block.c), and equal
			       distances go to the lower scene index */
};

struct rt_plane {
	rt_vec4 normal;	       /* unit; w: dot(normal, point), the plane's offset,
				  loaded with the normal (plane_offset) */
	rt_vec4 checker_color; /* w: checker square size (checker_size); the
				  struct has no room for a field of its own */
	rt_int material;
	rt_int has_checker;
	rt_int checker_s_axis; /* the two world axes kept for the checker pattern */
	rt_int checker_t_axis;
	rt_vec4 checker_origin; /* xyz: where the device's origin (the eye, which
				   the device's coordinates are relative to) lies
				   in the world, modulo twice the square size: the
				   pattern stays where the world has it; w: 0 */
};

struct rt_light {
	rt_vec4 position; /* relative to the eye, or for a directional light the
			     unit direction towards it; w: a sphere light's
			     radius, or tan of a directional light's angular
			     radius (0: a point, or a sharp directional light) */
	rt_vec4 color;	  /* w: 1 for a directional light, else 0. The w lanes
			     are read only in programs built with
			     RTCL_AREA_LIGHTS (RENDERING.md, "Light samples") */
};

/* A triangle: the indices of its three vertices in the vertex array and, in
 * w, its material index with RT_TRIANGLE_SMOOTH set when its shading normal
 * is interpolated from the vertices' (triangle_material, triangle_smooth).
 * One 16-byte load, then one per vertex: each vertex is stored once for all
 * the triangles that share it, which keeps a mesh within 64 device bytes per
 * triangle with its BVH (docs/bvh.md, "Triangle storage"). */
struct rt_triangle {
	rt_uvec4 index;
};

#define RT_TRIANGLE_SMOOTH 0x80000000u

/* A vertex's position (w unused), what the triangle test reads; and in an
 * array of its own, read only at a smooth triangle's hit, its unit shading
 * normal (0 at vertices of flat triangles). Vertex i's normal is element i. */
struct rt_vertex {
	rt_vec4 position;
};

struct rt_vertex_normal {
	rt_vec4 normal;
};

/* Textures (RENDERING.md, "Textures" and "Alpha cut-out"), in the block only
 * when a material has a texture or a cut-out, and read only in programs built
 * with RTCL_TEXTURES: a vertex's texture coordinates (vertex i's are element
 * i, read only at a hit of a textured or cut-out triangle, like the vertex
 * normals; 8 bytes, two to a 16-byte unit, the array padded to a whole
 * unit); per material what it takes from textures; per texture where its
 * texels are; the decode table of 8-bit texels (RT_TEXTURE_TABLE floats:
 * sRGB[i] = E^-1(i/255), then linear[i] = i/255); and the texels, each
 * texture's rows top first, 16-byte aligned, the block's last array (after
 * the path integrator's). */
struct rt_vertex_uv {
	rt_float u, v;
};

struct rt_material_map {
	rt_int texture;	       /* the base colour texture's index, or -1 */
	rt_int alpha_texture;  /* the cut-out's alpha texture's index, or -1 */
	rt_float alpha_cutoff; /* > 0: a hit of alpha below it is cut out; 0: none */
	rt_float alpha_scale;  /* the factor the texture's alpha is multiplied by */
};

struct rt_texture {
	rt_uint offset;	      /* of the texels, in bytes from the block's start */
	rt_int width, height; /* in texels */
	rt_uint flags;	      /* wrap_s | wrap_t << RT_WRAP_T_SHIFT | RT_TEXTURE_FLOAT */
};

#define RT_WRAP_REPEAT 0u
#define RT_WRAP_CLAMP 1u
#define RT_WRAP_MIRROR 2u
#define RT_WRAP_MASK 3u
#define RT_WRAP_T_SHIFT 2
/* Texels of 4 floats, linear (16-bit and float images); else 4 bytes, RGB
 * sRGB-encoded and alpha linear, decoded through the table. */
#define RT_TEXTURE_FLOAT 16u
/* 8-bit texels whose RGB are linear numbers (metallic-roughness), decoded
 * by the table's linear half. */
#define RT_TEXTURE_LINEAR 32u
#define RT_TEXTURE_TABLE 512

struct rt_scene {
	/* Camera, per docs/RENDERING.md: forward f, right r, up u. */
	rt_vec4 eye;	 /* w: a·h, the horizontal half-extent at distance 1 */
	rt_vec4 forward; /* w: h = tan(fov/2), the vertical half-extent */
	rt_vec4 right;	 /* w: epsilon, how far secondary rays start off the surface */
	rt_vec4 up;
	rt_vec4 background;
	rt_vec4 ambient;
	rt_int width, height, max_depth;
	rt_int sphere_slots; /* sphere_count rounded up to RT_SPHERE_GROUP: the
				array is padded with spheres nothing hits */
	rt_int material_count, sphere_count, plane_count, light_count;
	/* Byte offsets of the arrays from the start of this header. */
	rt_uint material_offset, sphere_offset, plane_offset, light_offset;
	rt_uint total_bytes;			/* the whole block, a multiple of 16 */
	rt_uint triangle_offset, vertex_offset; /* struct rt_triangle, rt_vertex */
	rt_int triangle_count;
	/* The BVH over the bounded primitives, spheres and triangles
	   (docs/bvh.md): bvh_node_count struct rt_bvh_node at bvh_node_offset,
	   node 0 the root, and the primitive references (rt_uint, RT_PRIM_*)
	   its leaves index at bvh_ref_offset. bvh_node_count is 0 with
	   --accel none or with neither spheres nor triangles. The triangle
	   fields took the header's last padding and these the next 16 bytes,
	   so that the header stays a multiple of 16 (the arrays after it are
	   read as float4). */
	rt_uint bvh_node_offset, bvh_ref_offset;
	rt_int bvh_node_count;
	rt_uint normal_offset; /* struct rt_vertex_normal, one per vertex */
	/* The leaves' triangles with their vertices inline, in leaf order
	   (struct rt_leaf_triangle; a leaf of triangles only names a range of
	   them, RT_LEAF_TRIANGLES); 0 without (--accel bvh-compact). */
	rt_uint bvh_triangle_offset;
	/* The thin lens (RENDERING.md, "The thin lens"): its radius A and the
	   focus distance F, read only in programs built with RTCL_THIN_LENS. */
	rt_float lens_radius, focus_distance;
	/* Textures (struct rt_texture above), read only in programs built with
	   RTCL_TEXTURES: struct rt_vertex_uv per vertex, struct rt_material_map
	   per material, texture_count struct rt_texture, the decode table. */
	rt_uint uv_offset;
	rt_uint material_map_offset, texture_offset, texture_table_offset;
	rt_int texture_count;
	/* The BVH's nodes: 2, struct rt_bvh_node; 4, struct rt_bvh4_node (a CPU
	   device outside the counting build, RTCL_BVH4); 0 without a BVH. */
	rt_int bvh_width;
	/* The path integrator's data (struct rt_path, RTCL_PATH): its byte
	   offset, 0 in a Whitted scene's block. */
	rt_uint path_offset;
	rt_int pad[2];
};

/* The path integrator (RENDERING.md, "Path tracing"), in the block only
 * under "integrator": "path" and read only in programs built with
 * RTCL_PATH: a header, a struct rt_bsdf per material, and the emitters (the
 * emissive triangles in scene order, then the emissive spheres) with the
 * cumulative distribution that chooses among them by power. */
struct rt_path {
	rt_uint bsdf_offset, emitter_offset; /* from the block's start */
	rt_int emitter_count;
	rt_int group_count;	      /* the light groups: lights, emitters, environment */
	rt_float inv_emitter_weight;  /* 1 / sum of lum(Le) * area over the emitters */
	rt_int environment;	      /* RT_ENVIRONMENT_*: what rays that leave see */
	rt_int env_width, env_height; /* the map's texels */
	/* The map (RENDERING.md, "The environment"): env_width * env_height
	   texels (float4, rgb the radiance with the scale, rows from the top),
	   the rows' cumulative distribution (env_height floats) and each row's
	   over its columns (env_width floats a row). */
	rt_uint env_texel_offset, env_row_cdf_offset, env_column_cdf_offset;
	rt_float env_inv_weight;      /* 1 / the sum of the texels' weights */
	rt_float env_cos, env_sin;    /* of the rotation about +y */
	rt_int env_is_light;	      /* a light group (its weights are not all 0) */
	rt_int pad;
};

#define RT_ENVIRONMENT_NONE 0	 /* black: no light */
#define RT_ENVIRONMENT_UNIFORM 1 /* the background's colour */
#define RT_ENVIRONMENT_MAP 2

/* A material's BSDF (SCENE.md "A material's bsdf"; the mapped one of a
 * material without: RENDERING.md). */
#define RT_BSDF_MAPPED 0
#define RT_BSDF_DIFFUSE 1
#define RT_BSDF_CONDUCTOR 2
#define RT_BSDF_DIELECTRIC 3
#define RT_BSDF_PRINCIPLED 4

struct rt_bsdf {
	rt_vec4 color;	  /* reflectance, F0 or base_color (the mapped BSDF takes the
			     material's colour at the hit instead); w: GGX alpha */
	rt_vec4 emission; /* Le from the front side; w: ior */
	rt_int type;	  /* RT_BSDF_* */
	rt_float metallic, transmission; /* principled */
	rt_float diffuse;		 /* mapped: kd */
	rt_float mirror;		 /* mapped: kr, the mirror's probability */
	rt_int mirror_tint;		 /* mapped: the mirror is a Schlick conductor of C */
	rt_int emits;			 /* emission is non-zero */
	rt_float roughness;		 /* principled: the factor, before its texture */
	/* A model's textures (RTCL_TEXTURES), indices or -1: glTF's
	   metallic-roughness (G scales the roughness, B the metallic factor)
	   and the emissive texture (multiplies the emission). */
	rt_int metallic_roughness_texture, emissive_texture;
	rt_int normal_texture; /* tangent space, linear: the shading normal */
	rt_int pad;
};

/* An emitter: the primitive (RT_PRIM_* kind | its device index) and the
 * cumulative probability up to and with it (the last 1). */
struct rt_emitter {
	rt_uint prim;
	rt_float cdf;
	rt_int pad[2];
};

/* A triangle of a leaf, its three vertex positions inline: v0.w holds its
 * scene index (int bits), what a hit names and ties compare. */
struct rt_leaf_triangle {
	rt_vec4 v0, v1, v2;
};

/* A BVH node of two children, both boxes in one 64-byte node so that one
 * visit loads four 16-byte words and tests two boxes (docs/bvh.md says why
 * two-wide). Child k's box is child[k].lo.xyz..child[k].hi.xyz, rounded
 * outward; the w lanes, read through bvh_child_index and bvh_child_count,
 * hold int bits: lo.w is the child node's index (an inner child) or its first
 * primitive reference (a leaf), hi.w is 0 for an inner child and the leaf's
 * reference count otherwise (0 with lo.w 0 too: an empty leaf, only beside a
 * root's single primitive). On the device a leaf of spheres only has
 * RT_LEAF_SPHERES in its count, and lo.w is its first sphere: the spheres
 * are in leaf order there (host/layout/scene_block.c). */
struct rt_bvh_box {
	rt_vec4 lo, hi;
};

struct rt_bvh_node {
	struct rt_bvh_box child[2];
};

/* A four-wide node (RTCL_BVH4, docs/bvh.md "A four-wide tree on CPUs"): the
 * binary tree collapsed, each node's children replaced by their own children,
 * the one of largest surface area first, until there are four or only leaves
 * left (host/layout/bvh.c, bvh_widen). The four boxes in SoA form, so that one
 * visit tests them in the four lanes of float4s: child k's box is (lo_x[k],
 * lo_y[k], lo_z[k])..(hi_x[k], hi_y[k], hi_z[k]); index[k] and count[k] are a
 * binary child's lo.w and hi.w (an inner child's index names a four-wide
 * node); a slot left empty has count RT_BVH4_EMPTY and a box no ray meets
 * (lo +FLT_MAX, hi -FLT_MAX). */
struct rt_bvh4_node {
	rt_vec4 lo_x, lo_y, lo_z, hi_x, hi_y, hi_z;
	rt_int index[4], count[4];
};

#define RT_BVH4_EMPTY (-1)

/* A device leaf of spheres only: the count's flag (see struct rt_bvh_box). */
#define RT_LEAF_SPHERES 0x40000000
#define RT_LEAF_TRIANGLES 0x20000000
#define RT_LEAF_COUNT_MASK 0x1fffffff

/* A primitive reference: the kind in the top bit, the index into the kind's
 * array below it. */
#define RT_PRIM_KIND_SHIFT 31
#define RT_PRIM_SPHERE 0u
#define RT_PRIM_TRIANGLE 1u
#define RT_PRIM_INDEX_MASK 0x7fffffffu

/* The deepest BVH the builder makes (the root at depth 0), which sizes the
 * tracer's traversal stack: each level leaves at most one child waiting. */
#define RT_BVH_MAX_DEPTH 64

/* Counts per launched work-item in the counting build: flops, rays, BVH
 * node visits, leaf visits and primitive tests in those leaves, then,
 * measured on NVIDIA devices (RTCL_SIMD_MEASURE, docs/RENDERING.md "SIMD
 * efficiency, measured"; 0 elsewhere), for each phase the steps this
 * work-item took and the warp-steps it led; then, under the path
 * integrator (0 under Whitted), its paths by length (RENDERING.md, "Paths
 * per bounce"): RT_PATH_LENGTH_BINS counts, bin b the paths of b + 1
 * segments and the last bin those of RT_PATH_LENGTH_BINS or more, the
 * longest path's segments and the sum of every path's. */
#define RT_ITEM_FLOPS 0
#define RT_ITEM_RAYS 1
#define RT_ITEM_NODE_VISITS 2
#define RT_ITEM_LEAF_VISITS 3
#define RT_ITEM_PRIM_TESTS 4
#define RT_SIMD_PHASES 3 /* RT_SIMD_INTERSECT, RT_SIMD_TRAVERSAL, RT_SIMD_SHADE */
#define RT_SIMD_INTERSECT 0 /* a ray or shadow ray's intersection and shading step */
#define RT_SIMD_TRAVERSAL 1 /* an iteration of the BVH traversal loop */
#define RT_SIMD_SHADE 2	    /* a path vertex's BSDF sample, in its BSDF kind's branch */
#define RT_ITEM_LANE_STEPS(phase) (5 + 2 * (phase))
#define RT_ITEM_WARP_STEPS(phase) (6 + 2 * (phase))
#define RT_PATH_LENGTH_BINS 16
#define RT_ITEM_PATH_LENGTHS (5 + 2 * RT_SIMD_PHASES) /* the first bin */
#define RT_ITEM_PATH_MAX (RT_ITEM_PATH_LENGTHS + RT_PATH_LENGTH_BINS)
#define RT_ITEM_PATH_SEGMENTS (RT_ITEM_PATH_MAX + 1)
#define RT_ITEM_COUNTS (RT_ITEM_PATH_SEGMENTS + 1)

/* The probe buffer of the single-pass kernels: with RTCL_COUNT_WRITES (the
 * tests), one write count per pixel; with RTCL_SCHEDULE_MAP (--schedule-map,
 * docs/RENDERING.md), RT_SCHEDULE_WORDS per pixel (its work-group, its
 * work-item in the group, its ticket), then the ticket counter; otherwise a
 * placeholder. */
#define RT_SCHEDULE_WORDS 3
#define RT_SCHEDULE_GROUP 0
#define RT_SCHEDULE_ITEM 1
#define RT_SCHEDULE_TICKET 2

/* The single-pass kernels' work counter: RT_COUNTER_WORDS uints that the
 * host zeroes before every launch. Word RT_COUNTER_NEXT hands out work (the
 * next chunk of dynamic, the next pixel of persistent); word RT_COUNTER_DONE
 * counts, in a build with RTCL_PROGRESS, the pixels of whole chunks that
 * serial, naive and cyclic have done, one atomic_add per chunk. The host
 * reads both while a launch runs, for the progress line (host/render/watch.h). */
#define RT_COUNTER_NEXT 0
#define RT_COUNTER_DONE 1
#define RT_COUNTER_WORDS 2

/* A ray waiting in the wavefront kernel's queue. */
struct rt_ray {
	rt_vec4 origin; /* w: weight, the product of kr/kt along the path
			   (ray_weight), stored and loaded with the origin */
	rt_vec4 dir;	/* unit */
	rt_int pixel;	/* y * width + x */
	rt_int depth;
	rt_float weight_green, weight_blue; /* with colour weights (RTCL_FRESNEL):
					       the weight's other channels, red
					       in origin.w */
};

/* A path waiting in the wavefront kernel's queue under the path integrator
 * (RTCL_PATH; cl/path.cl's struct walk between two bounces): the next
 * segment, the throughput in the w lanes, and the MIS state. */
struct rt_path_ray {
	rt_vec4 origin; /* w: the throughput's red */
	rt_vec4 dir;	/* unit; w: its green */
	rt_vec4 x_prev; /* where the last BSDF sample was taken; w: blue */
	rt_int pixel;	/* y * width + x */
	rt_int vertex;	/* of the next hit */
	rt_float pdf_prev;
	rt_int specular;
};

/* The stages form of the wavefront under the path integrator
 * (docs/wavefront.md, "The stages form"): a pool of `slots` paths whose
 * state lies in structure-of-arrays, RT_STAGE_FIELDS arrays of `slots`
 * 16-byte words one after another (cl/wavefront.cl says what each holds),
 * and RT_STAGE_QUEUES queues of `slots` slot indices, each with its length
 * in the counter word of the same number (RT_STAGE_COUNTERS words, padded
 * so that the 64-bit count of the paths handed out follows aligned). */
#define RT_STAGE_RAY_O 0    /* the next segment's origin; w: the throughput's red */
#define RT_STAGE_RAY_D 1    /* its direction; w: green */
#define RT_STAGE_PREV 2	    /* where the last BSDF sample was taken; w: blue */
#define RT_STAGE_COLOR 3    /* the radiance gathered; w: the last BSDF pdf */
#define RT_STAGE_PATH 4	    /* ints: pixel, sample, vertex, RT_PATH_* flags */
#define RT_STAGE_HIT 5	    /* the segment's hit: t, u, v, triangle (int) */
#define RT_STAGE_HIT_PRIM 6 /* ints: its sphere, plane; the shadow ray clear */
#define RT_STAGE_SHADOW_O 7 /* the shadow ray's origin; w: its length */
#define RT_STAGE_SHADOW_D 8 /* its direction; w: the emitter sphere (int) */
#define RT_STAGE_SHADOW_C 9 /* what it brings; w: the emitter triangle (int) */
#define RT_STAGE_FIELDS 10
#define RT_PATH_LIVE 1u	    /* the slot holds a path */
#define RT_PATH_SPECULAR 2u /* its last scattering was a delta lobe (or none) */
#define RT_PATH_SHADOW 4u   /* a shadow ray was queued for it, its light not added */
#define RT_PATH_DONE 8u	    /* it ends once that shadow ray is traced */
#define RT_STAGE_QUEUE_NEW 0			 /* free slots, for new paths (a stack) */
#define RT_STAGE_QUEUE_SHADE(kind) (1 + (kind)) /* paths at a hit of kind RT_BSDF_* */
#define RT_STAGE_KINDS 5
#define RT_STAGE_QUEUE_EXTEND 6 /* segments to trace (nearest hit) */
#define RT_STAGE_QUEUE_SHADOW 7 /* shadow rays to trace (any hit) */
#define RT_STAGE_QUEUE_DECIDE 8 /* paths that ended: done at a hit, or missed */
#define RT_STAGE_QUEUES 9
#define RT_STAGE_COUNTERS 10

/* What one launch (or one wavefront pass) renders: a rectangle of the image
 * and a range of each of its pixels' samples. A plain render is one or more
 * pieces covering the whole image; a multi-device render hands pieces to
 * several devices. The kernels write the full-image buffers at the pixels'
 * own positions, y * width + x, where y is the image row of the rectangle's
 * row (rt_piece_row). */
struct rt_piece {
	rt_int x0, y0, width, height;	 /* a rectangle of split rows (rt_piece_row),
					    in pixels */
	rt_int sample_begin, sample_end; /* the samples of each pixel traced now:
					    [begin, end) */
	rt_int samples;			 /* N, samples per pixel of the whole render */
	rt_int row_band;		 /* 0: split row v is image row v; else the
					    height of the bands rt_piece_row deals */
	rt_int row_bands;		 /* the image's whole bands of row_band rows */
	rt_int row_classes;		 /* the classes they are dealt to (>= 2) */
	rt_int sum_begin;		 /* the first sample whose colour the sums
					    buffer holds (0 unless the samples
					    are split between devices): a pass
					    adds to the sums it holds when
					    sample_begin > sum_begin, and stores
					    the mean when sample_end == samples
					    and sum_begin == 0 */
	rt_float mean_scale;		 /* 1 / (samples * RT_SUM_ONE), rounded to
					    float: what the sum is multiplied by
					    for the mean (set by the host at each
					    launch, rt_mean_scale) */
};

/* A pixel's samples are summed in fixed point (docs/RENDERING.md, "Samples
 * per pixel"): each channel of a sample's colour c becomes the integer
 * round(c * RT_SUM_ONE) in a 64-bit sum, so that the sum does not depend on
 * the order the samples are added in and samples can be split between
 * devices. A pixel's sum is 4 such integers: the channels' sums and a word
 * of saturation marks (cl/sample.cl). A channel of RT_SUM_LIMIT or more, or
 * NaN, saturates (sample_fixed returns RT_SUM_SATURATED): it adds nothing,
 * its mark stays, and its mean is +inf (written as the format's largest
 * value); one of -RT_SUM_LIMIT or less counts as -RT_SUM_LIMIT. RT_SUM_LIMIT
 * * RT_SUM_ONE * 65536 samples (SCENE_MAX_SAMPLES) is 2^62: a sum never
 * overflows. */
#define RT_SUM_ONE 0x1p24f
#define RT_SUM_LIMIT 0x1p22f
#define RT_SUM_SATURATED 0x7fffffffffffffffL

/* The image row of split row v of a piece (docs/GUIDE.md, "How the rows are
 * ordered"): with row_band 0, v itself. Else the image's whole bands of
 * row_band rows are dealt to S = row_classes classes (band i to class
 * i mod S), and the split bands are class 0's bands top to bottom (0, S, 2S,
 * ..), then class 1's (1, S + 1, ..), and so on: with F = qS + r bands, the
 * first r classes have q + 1. A run of F/S split bands is thus every S-th
 * band of the image; the rows after the last whole band stay where they are.
 * Shared by the kernels and the host (which copies and checks pieces by it). */
static inline rt_int rt_piece_row(const struct rt_piece *p, rt_int v)
{
	if (p->row_band == 0 || v >= p->row_band * p->row_bands)
		return v;
	rt_int b = v / p->row_band;
	rt_int q = p->row_bands / p->row_classes, r = p->row_bands % p->row_classes;
	rt_int c, k; /* split band b is band k of class c */
	if (b < r * (q + 1)) {
		c = b / (q + 1);
		k = b - c * (q + 1);
	} else {
		c = r + (b - r * (q + 1)) / q;
		k = b - r * (q + 1) - (c - r) * q;
	}
	return (c + k * p->row_classes) * p->row_band + (v - b * p->row_band);
}

#ifndef __OPENCL_VERSION__
#include <stddef.h>
_Static_assert(sizeof(struct rt_piece) == 48, "rt_piece layout");
_Static_assert(offsetof(struct rt_piece, sample_begin) == 16, "rt_piece layout");
_Static_assert(offsetof(struct rt_piece, samples) == 24, "rt_piece layout");
_Static_assert(sizeof(struct rt_ray) == 48, "rt_ray layout");
_Static_assert(sizeof(struct rt_path_ray) == 64, "rt_path_ray layout");
_Static_assert(sizeof(struct rt_material) == 48, "rt_material layout");
_Static_assert(sizeof(struct rt_sphere) == 32, "rt_sphere layout");
_Static_assert(offsetof(struct rt_sphere, material) == 24, "rt_sphere layout");
_Static_assert(sizeof(struct rt_plane) == 64, "rt_plane layout");
_Static_assert(offsetof(struct rt_plane, checker_origin) == 48, "rt_plane layout");
_Static_assert(offsetof(struct rt_plane, material) == 32, "rt_plane layout");
_Static_assert(sizeof(struct rt_light) == 32, "rt_light layout");
_Static_assert(sizeof(struct rt_triangle) == 16, "rt_triangle layout");
_Static_assert(sizeof(struct rt_vertex) == 16, "rt_vertex layout");
_Static_assert(sizeof(struct rt_vertex_normal) == 16, "rt_vertex_normal layout");
_Static_assert(sizeof(struct rt_scene) == 224, "rt_scene layout");
_Static_assert(sizeof(struct rt_bvh4_node) == 128, "rt_bvh4_node layout");
_Static_assert(offsetof(struct rt_scene, uv_offset) == 188, "rt_scene layout");
_Static_assert(sizeof(struct rt_vertex_uv) == 8, "rt_vertex_uv layout");
_Static_assert(sizeof(struct rt_material_map) == 16, "rt_material_map layout");
_Static_assert(sizeof(struct rt_texture) == 16, "rt_texture layout");
_Static_assert(sizeof(struct rt_leaf_triangle) == 48, "rt_leaf_triangle layout");
_Static_assert(offsetof(struct rt_scene, width) == 96, "rt_scene layout");
_Static_assert(offsetof(struct rt_scene, material_offset) == 128, "rt_scene layout");
_Static_assert(offsetof(struct rt_scene, triangle_offset) == 148, "rt_scene layout");
_Static_assert(offsetof(struct rt_scene, bvh_node_offset) == 160, "rt_scene layout");
_Static_assert(sizeof(struct rt_scene) % 16 == 0,
	       "rt_scene: the arrays after it stay 16-byte aligned");
_Static_assert(sizeof(struct rt_bvh_node) == 64, "rt_bvh_node layout");
_Static_assert(offsetof(struct rt_scene, path_offset) == 212, "rt_scene layout");
_Static_assert(sizeof(struct rt_path) == 64, "rt_path layout");
_Static_assert(sizeof(struct rt_bsdf) == 80, "rt_bsdf layout");
_Static_assert(sizeof(struct rt_emitter) == 16, "rt_emitter layout");
_Static_assert(offsetof(struct rt_bvh_node, child[1].lo) == 32, "rt_bvh_node layout");
#endif

/* The scalars that share a 16-byte load with a vector, by name. They take the
 * float4 already loaded, so that reading the scalar adds no load. */
#ifdef __OPENCL_VERSION__
/* center: struct rt_sphere's centre lane */
static inline float sphere_radius2(float4 center)
{
	return center.w;
}

/* normal: struct rt_plane's normal lane */
static inline float plane_offset(float4 normal)
{
	return normal.w;
}

/* color: struct rt_material's colour lane */
static inline float material_ambient(float4 color)
{
	return color.w;
}

/* index: struct rt_triangle's material lane */
static inline int triangle_material(uint4 index)
{
	return (int)(index.w & ~RT_TRIANGLE_SMOOTH);
}

static inline bool triangle_smooth(uint4 index)
{
	return (index.w & RT_TRIANGLE_SMOOTH) != 0;
}

/* checker_color: struct rt_plane's checker lane */
static inline float checker_size(float4 checker_color)
{
	return checker_color.w;
}

/* lo, hi: a struct rt_bvh_box's corners. The child's node index or first
 * primitive reference, and its reference count (0: an inner node). */
static inline int bvh_child_index(float4 lo)
{
	return as_int(lo.w);
}

static inline int bvh_child_count(float4 hi)
{
	return as_int(hi.w);
}

/* origin: struct rt_ray's origin lane */
static inline float ray_weight(float4 origin)
{
	return origin.w;
}
#endif

#endif
