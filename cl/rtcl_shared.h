/* Everything that crosses the host/device boundary, written once and included
 * both by the C host and by OpenCL C (STYLE.md rule 2).
 *
 * The device scene is one contiguous block: a struct rt_scene header, then the
 * material, sphere, plane and light arrays at the byte offsets the header
 * gives. Every struct is a whole number of 16-byte units so that the block can
 * be copied into __local memory as uint4 words. Vectors are float4 on both
 * sides (cl_float4 on the host) with w unused unless noted.
 */
#ifndef RTCL_SHARED_H
#define RTCL_SHARED_H

#ifdef __OPENCL_VERSION__
typedef float4 rt_vec4;
typedef float rt_float;
typedef int rt_int;
typedef uint rt_uint;
#else
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl_platform.h>
typedef cl_float4 rt_vec4;
typedef cl_float rt_float;
typedef cl_int rt_int;
typedef cl_uint rt_uint;
#endif

struct rt_material {
	rt_vec4 color;	    /* C; w: ka */
	rt_float diffuse;   /* kd */
	rt_float specular;  /* ks */
	rt_float shininess; /* Blinn-Phong exponent */
	rt_float reflect;   /* kr */
	rt_float transmit;  /* kt */
	rt_float ior;
	rt_float inv_ior; /* 1/ior, the eta of a ray entering the object */
	rt_float pad;
};

/* The tracer tests spheres this many at a time. */
#define RT_SPHERE_GROUP 4

struct rt_sphere {
	rt_vec4 center;	     /* w: radius², so that one 16-byte load feeds a test;
				-1 in the padding, which nothing hits */
	rt_float radius;
	rt_float inv_radius; /* 1/radius */
	rt_int material;
	rt_int pad;
};

struct rt_plane {
	rt_vec4 normal;	       /* unit; w: dot(normal, point), the plane's offset */
	rt_vec4 checker_color; /* w: checker square size */
	rt_int material;
	rt_int has_checker;
	rt_int checker_s_axis; /* the two world axes kept for the checker pattern */
	rt_int checker_t_axis;
};

struct rt_light {
	rt_vec4 position;
	rt_vec4 color;
};

struct rt_scene {
	/* Camera, per RENDERING.md: forward f, right r, up u; w fields: */
	rt_vec4 eye;	 /* w: a·h, the horizontal half-extent */
	rt_vec4 forward; /* w: h = tan(fov/2), the vertical half-extent */
	rt_vec4 right;	 /* w: epsilon */
	rt_vec4 up;
	rt_vec4 background;
	rt_vec4 ambient;
	rt_int width, height, max_depth;
	rt_int sphere_slots; /* sphere_count rounded up to RT_SPHERE_GROUP: the
				array is padded with spheres nothing hits */
	rt_int material_count, sphere_count, plane_count, light_count;
	/* Byte offsets of the arrays from the start of this header. */
	rt_uint material_offset, sphere_offset, plane_offset, light_offset;
	rt_uint total_bytes; /* the whole block, a multiple of 16 */
	rt_uint pad1, pad2, pad3;
};

/* A ray waiting in the wavefront kernel's queue. */
struct rt_ray {
	rt_vec4 origin; /* w: weight, the product of kr/kt along the path */
	rt_vec4 dir;	/* unit */
	rt_int pixel;	/* y * width + x */
	rt_int depth;
	rt_int pad0, pad1;
};

#ifndef __OPENCL_VERSION__
#include <stddef.h>
_Static_assert(sizeof(struct rt_ray) == 48, "rt_ray layout");
_Static_assert(sizeof(struct rt_material) == 48, "rt_material layout");
_Static_assert(sizeof(struct rt_sphere) == 32, "rt_sphere layout");
_Static_assert(offsetof(struct rt_sphere, material) == 24, "rt_sphere layout");
_Static_assert(sizeof(struct rt_plane) == 48, "rt_plane layout");
_Static_assert(offsetof(struct rt_plane, material) == 32, "rt_plane layout");
_Static_assert(sizeof(struct rt_light) == 32, "rt_light layout");
_Static_assert(sizeof(struct rt_scene) == 160, "rt_scene layout");
_Static_assert(offsetof(struct rt_scene, width) == 96, "rt_scene layout");
_Static_assert(offsetof(struct rt_scene, material_offset) == 128, "rt_scene layout");
#endif

#endif
