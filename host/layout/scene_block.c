#include "layout/scene_block.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "base/quote.h"
#include "base/vec3.h"

static rt_vec4 vec4(const double v[3], double w)
{
	rt_vec4 out = {{(float)v[0], (float)v[1], (float)v[2], (float)w}};
	return out;
}

static size_t round16(size_t bytes)
{
	return (bytes + 15) / 16 * 16;
}

static void pack_camera(struct rt_scene *out, const struct scene *scene, int width, int height)
{
	const struct scene_camera *cam = &scene->camera;
	double forward[3], right[3], up[3];
	double h = tan(cam->fov * M_PI / 360.0);
	double aspect = (double)width / height;

	for (int i = 0; i < 3; i++)
		forward[i] = cam->look_at[i] - cam->eye[i];
	vec3_normalize(forward);
	vec3_cross(forward, cam->up, right);
	vec3_normalize(right);
	vec3_cross(right, forward, up);

	/* The scalars in w: scene_half_width, scene_half_height, scene_epsilon. */
	static const double origin[3] = {0, 0, 0}; /* the eye: scene_from_eye */

	out->eye = vec4(origin, aspect * h);
	out->forward = vec4(forward, h);
	out->right = vec4(right, scene->epsilon);
	out->up = vec4(up, 0.0);
	out->lens_radius = (float)cam->aperture;
	out->focus_distance = (float)cam->focus_distance;
}

static void pack_material(struct rt_material *out, const struct scene_material *in)
{
	out->color = vec4(in->color, in->ambient); /* ka in w: material_ambient */
	out->diffuse = (float)in->diffuse;
	out->specular = (float)in->specular;
	out->shininess = (float)in->shininess;
	out->reflect = (float)in->reflect;
	out->transmit = (float)in->transmit;
	out->ior = (float)in->ior;
	out->inv_ior = (float)(1.0 / in->ior);
	out->fresnel = in->fresnel;
}

static void pack_sphere(struct rt_sphere *out, const struct scene *scene,
			const struct scene_sphere *in, int scene_index)
{
	double center[3];

	scene_from_eye(scene, in->center, center);
	out->center = vec4(center, in->radius * in->radius); /* sphere_radius2 */
	out->radius = (float)in->radius;
	out->inv_radius = (float)(1.0 / in->radius);
	out->material = in->material;
	out->scene_index = scene_index;
}

static void pack_plane(struct rt_plane *out, const struct scene *scene,
		       const struct scene_plane *in)
{
	const double *n = in->normal;
	double point[3], origin[3];
	int drop = 0;

	scene_from_eye(scene, in->point, point);
	/* The eye modulo twice the square size: the checker's parity is the
	 * same, and the offset small enough for float to keep. */
	for (int i = 0; i < 3; i++) {
		double period = 2.0 * in->checker_size;
		origin[i] = in->has_checker ? fmod(scene->camera.eye[i], period) : 0.0;
		if (origin[i] < 0)
			origin[i] += period;
	}

	/* The checker drops the axis of the normal's largest |component|,
	 * ties going to x, then y. */
	if (fabs(n[1]) > fabs(n[drop]))
		drop = 1;
	if (fabs(n[2]) > fabs(n[drop]))
		drop = 2;
	/* The offset and the square size ride in w (plane_offset, checker_size). */
	out->normal = vec4(n, vec3_dot(n, point));
	out->checker_origin = vec4(origin, 0.0);
	out->checker_color = vec4(in->checker_color, in->checker_size);
	out->material = in->material;
	out->has_checker = in->has_checker;
	out->checker_s_axis = drop == 0 ? 1 : 0;
	out->checker_t_axis = drop == 2 ? 1 : 2;
}

/* A light as the tracer reads it (cl/rtcl_shared.h): a directional light as
 * the unit way towards it, which the eye's translation leaves as it is. */
static void pack_light(struct rt_light *out, const struct scene *scene,
		       const struct scene_light *in)
{
	double position[3];

	if (in->directional) {
		double toward[3] = {-in->direction[0], -in->direction[1], -in->direction[2]};
		out->position = vec4(toward, tan(in->angle * M_PI / 180.0));
		out->color = vec4(in->color, 1.0);
		return;
	}
	scene_from_eye(scene, in->position, position);
	out->position = vec4(position, in->radius);
	out->color = vec4(in->color, 0.0);
}

static int is_sphere_ref(uint32_t ref)
{
	return ref >> RT_PRIM_KIND_SHIFT == RT_PRIM_SPHERE;
}

/* With a BVH the spheres go to the device in leaf order: the k-th sphere
 * reference of bvh->refs is device sphere k (order[k] gives its scene index),
 * so a leaf of spheres only names a range of the sphere array and the
 * traversal reads no reference on the way to a sphere test (RT_LEAF_SPHERES).
 * Returns order (sphere_count entries, malloc'd; identity without a BVH), or
 * NULL when out of memory. */
static int *sphere_order(const struct scene *scene, const struct bvh *bvh)
{
	int *order = malloc((size_t)(scene->sphere_count ? scene->sphere_count : 1) * sizeof(int));
	int k = 0;

	if (!order)
		return NULL;
	if (!bvh || bvh->node_count == 0) {
		for (int i = 0; i < scene->sphere_count; i++)
			order[i] = i;
		return order;
	}
	for (int r = 0; r < bvh->ref_count; r++)
		if (is_sphere_ref(bvh->refs[r]))
			order[k++] = (int)(bvh->refs[r] & RT_PRIM_INDEX_MASK);
	return order;
}

/* A leaf child whose references are all spheres becomes a range of the
 * sphere array: its first device sphere, and its count with
 * RT_LEAF_SPHERES; one whose references are all triangles a range of the
 * leaf triangles (RT_LEAF_TRIANGLES). before[r]: references of r's kind
 * before r. */
static void leaf_to_range(int32_t *first_out, int32_t *count_out, const struct bvh *bvh,
			  const int *before)
{
	int32_t first = *first_out, count = *count_out;
	int spheres = 0;

	if (count <= 0)
		return;
	for (int r = first; r < first + count; r++)
		spheres += is_sphere_ref(bvh->refs[r]);
	if (spheres != 0 && spheres != count)
		return;
	if (spheres == 0 && !bvh->leaf_triangles)
		return;
	*first_out = before[first];
	*count_out = count | (spheres ? RT_LEAF_SPHERES : RT_LEAF_TRIANGLES);
}

/* leaf_to_range for a binary node's child, whose w lanes hold the pair. */
static void box_leaf_to_range(struct rt_bvh_box *child, const struct bvh *bvh, const int *before)
{
	int32_t first, count;

	memcpy(&first, &child->lo.s[3], sizeof(first));
	memcpy(&count, &child->hi.s[3], sizeof(count));
	leaf_to_range(&first, &count, bvh, before);
	memcpy(&child->lo.s[3], &first, sizeof(first));
	memcpy(&child->hi.s[3], &count, sizeof(count));
}

/* Leaf triangle k: triangle i's vertex positions, i in v0.w. */
static void pack_leaf_triangle(struct rt_leaf_triangle *out, const struct mesh_block *mesh,
			       int32_t i)
{
	const struct rt_triangle *t = &mesh->triangles[i];

	out->v0 = mesh->vertices[t->index.s[0]].position;
	out->v1 = mesh->vertices[t->index.s[1]].position;
	out->v2 = mesh->vertices[t->index.s[2]].position;
	memcpy(&out->v0.s[3], &i, sizeof(i));
}

/* The BVH's nodes and references, after the triangles (none without a BVH),
 * with the spheres in leaf order (sphere_order): sphere references name
 * device spheres, leaves of spheres are ranges; and the triangles in leaf
 * order with their vertices inline, leaves of triangles ranges of them.
 * Returns 0, or -1 when out of memory. */
static int pack_bvh(unsigned char *block, struct rt_scene *header, const struct bvh *bvh,
		    const struct mesh_block *mesh)
{
	unsigned char *nodes = block + header->bvh_node_offset;
	uint32_t *refs = (uint32_t *)(block + header->bvh_ref_offset);
	struct rt_leaf_triangle *leaf_triangles =
		(struct rt_leaf_triangle *)(block + header->bvh_triangle_offset);
	int *before, spheres = 0, triangles = 0;

	if (!bvh || bvh->node_count == 0)
		return 0;
	before = malloc((size_t)bvh->ref_count * sizeof(int));
	if (!before)
		return -1;
	header->bvh_node_count = bvh->wide ? bvh->wide_count : bvh->node_count;
	header->bvh_width = bvh->wide ? 4 : 2;
	for (int r = 0; r < bvh->ref_count; r++) {
		if (is_sphere_ref(bvh->refs[r])) {
			before[r] = spheres;
			refs[r] = (RT_PRIM_SPHERE << RT_PRIM_KIND_SHIFT) | spheres++;
		} else {
			before[r] = triangles;
			refs[r] = bvh->refs[r];
			if (bvh->leaf_triangles)
				pack_leaf_triangle(&leaf_triangles[triangles], mesh,
						   (int32_t)(bvh->refs[r] & RT_PRIM_INDEX_MASK));
			triangles++;
		}
	}
	if (bvh->wide) {
		struct rt_bvh4_node *wide = (struct rt_bvh4_node *)nodes;
		memcpy(wide, bvh->wide, (size_t)bvh->wide_count * sizeof(*wide));
		for (int n = 0; n < bvh->wide_count; n++)
			for (int c = 0; c < 4; c++)
				if (wide[n].count[c] != RT_BVH4_EMPTY)
					leaf_to_range(&wide[n].index[c], &wide[n].count[c], bvh,
						      before);
	} else {
		struct rt_bvh_node *binary = (struct rt_bvh_node *)nodes;
		memcpy(binary, bvh->nodes, (size_t)bvh->node_count * sizeof(*binary));
		for (int n = 0; n < bvh->node_count; n++)
			for (int c = 0; c < 2; c++)
				box_leaf_to_range(&binary[n].child[c], bvh, before);
	}
	free(before);
	return 0;
}

/* The leaf triangles of a BVH: its triangle references, with
 * bvh->leaf_triangles; none without. */
static size_t leaf_triangle_count(const struct bvh *bvh)
{
	size_t n = 0;

	for (int r = 0; bvh && bvh->leaf_triangles && r < bvh->ref_count; r++)
		n += !is_sphere_ref(bvh->refs[r]);
	return n;
}

/* Where the arrays go in the block (byte offsets) and its size. The
 * textures' arrays (uv ... texture_table, and the texels, the block's last
 * array, after the path integrator's) only in a scene with textures
 * (scene_has_textures), else they are empty. */
struct layout {
	size_t material, sphere, plane, light, triangle, vertex, normal, node, ref, leaf_triangle,
		uv, material_map, texture, texture_table, texel, path, bsdf, emitter, env_texel,
		env_row_cdf, env_column_cdf, total;
	size_t head; /* what scene_block_pack_head packs: all before the texels */
	int sphere_slots;
};

/* The emitters of the path integrator: the triangles and spheres whose
 * material emits (RENDERING.md, "Lights and their selection"). */
static int emitter_count(const struct scene *scene)
{
	int n = 0;

	for (int i = 0; i < scene->triangle_count; i++)
		n += scene_material_emits(&scene->materials[scene->triangles[i].material]);
	for (int i = 0; i < scene->sphere_count; i++)
		n += scene_material_emits(&scene->materials[scene->spheres[i].material]);
	return n;
}

/* The path integrator's arrays after everything else, only in a scene
 * it renders: the block of a Whitted scene is as before. */
static void layout_path(struct layout *l, const struct scene *scene)
{
	const struct scene_environment *env = &scene->environment;
	size_t texels = env->rgb ? (size_t)env->width * env->height : 0;

	l->path = l->bsdf = l->emitter = l->env_texel = l->env_row_cdf = l->env_column_cdf =
		l->total;
	if (scene->integrator != SCENE_INTEGRATOR_PATH)
		return;
	l->path = round16(l->total);
	l->bsdf = l->path + sizeof(struct rt_path);
	l->emitter = l->bsdf + (size_t)scene->material_count * sizeof(struct rt_bsdf);
	/* The map's texels and column CDFs last, after its row CDF: a renderer
	 * writes them from the scene (scene_block_env_rows). */
	l->env_row_cdf = l->emitter + (size_t)emitter_count(scene) * sizeof(struct rt_emitter);
	l->env_texel =
		round16(l->env_row_cdf + (env->rgb ? (size_t)env->height : 0) * sizeof(float));
	l->env_column_cdf = l->env_texel + texels * sizeof(rt_vec4);
	l->total = round16(l->env_column_cdf + texels * sizeof(float));
}

static struct layout layout_of(const struct scene *scene, const struct mesh_block *mesh,
			       const struct bvh *bvh)
{
	struct layout l;

	l.material = round16(sizeof(struct rt_scene));
	l.sphere = l.material + (size_t)scene->material_count * sizeof(struct rt_material);
	l.sphere_slots =
		(scene->sphere_count + RT_SPHERE_GROUP - 1) / RT_SPHERE_GROUP * RT_SPHERE_GROUP;
	l.plane = l.sphere + (size_t)l.sphere_slots * sizeof(struct rt_sphere);
	l.light = l.plane + (size_t)scene->plane_count * sizeof(struct rt_plane);
	l.triangle = l.light + (size_t)scene->light_count * sizeof(struct rt_light);
	l.vertex = l.triangle + (size_t)scene->triangle_count * sizeof(struct rt_triangle);
	l.normal = l.vertex + (size_t)mesh->vertex_count * sizeof(struct rt_vertex);
	l.node = l.normal + (size_t)mesh->vertex_count * sizeof(struct rt_vertex_normal);
	l.ref = l.node + (!bvh	      ? 0
			  : bvh->wide ? (size_t)bvh->wide_count * sizeof(*bvh->wide)
				      : (size_t)bvh->node_count * sizeof(*bvh->nodes));
	l.leaf_triangle = round16(l.ref + (bvh ? (size_t)bvh->ref_count * sizeof(*bvh->refs) : 0));
	l.uv = l.leaf_triangle + leaf_triangle_count(bvh) * sizeof(struct rt_leaf_triangle);
	l.material_map = l.texture = l.texture_table = l.texel = l.total = l.uv;
	if (!scene_has_textures(scene)) {
		layout_path(&l, scene);
		l.texel = l.total; /* none: scene_block_pack_head packs the whole block */
		l.head = scene->environment.rgb ? l.env_texel : l.texel;
		return l;
	}
	l.material_map = round16(l.uv + (size_t)mesh->vertex_count * sizeof(struct rt_vertex_uv));
	l.texture = l.material_map + (size_t)scene->material_count * sizeof(struct rt_material_map);
	l.texture_table = l.texture + (size_t)scene->texture_count * sizeof(struct rt_texture);
	l.total = l.texture_table + RT_TEXTURE_TABLE * sizeof(float);
	layout_path(&l, scene);
	/* The texels last, so that all else is one block before them, which a
	 * renderer packs without them (scene_block_pack_head). */
	l.texel = round16(l.total);
	l.total = l.texel + scene_texture_bytes(scene);
	l.head = scene->environment.rgb ? l.env_texel : l.texel;
	return l;
}

static double luminance(const double c[3])
{
	return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

/* A material's BSDF as the path integrator reads it (RENDERING.md, "The
 * BSDFs"): its own, or the mapping of the Whitted fields. */
static void pack_bsdf(struct rt_bsdf *out, const struct scene_material *m)
{
	const struct scene_bsdf *b = &m->bsdf;
	double ior = b->ior, roughness = b->roughness;

	memset(out, 0, sizeof(*out));
	out->type = b->type; /* SCENE_BSDF_* are RT_BSDF_* */
	if (b->type == SCENE_BSDF_NONE && m->transmit > 0) {
		out->type = RT_BSDF_DIELECTRIC; /* glass stays glass, smooth */
		ior = m->ior;
		roughness = 0;
	} else if (b->type == SCENE_BSDF_NONE) {
		ior = m->ior; /* unused by the mapped BSDF, but a number */
		out->diffuse = (float)m->diffuse;
		out->mirror = (float)m->reflect;
		out->mirror_tint = m->fresnel == SCENE_FRESNEL_CONDUCTOR;
	}
	double alpha = roughness * roughness;
	if (b->type == SCENE_BSDF_PRINCIPLED && alpha < 0.001)
		alpha = 0.001; /* RENDERING.md: no delta lobes */
	out->color = vec4(b->color, alpha);
	out->emission = vec4(m->emission, ior);
	out->metallic = (float)b->metallic;
	out->transmission = (float)b->transmission;
	out->emits = scene_material_emits(m);
	out->roughness = (float)roughness;
	out->metallic_roughness_texture = m->metallic_roughness_texture - 1;
	out->emissive_texture = m->emissive_texture - 1;
	out->normal_texture = m->normal_texture - 1;
}

/* Emitter weights (RENDERING.md, "Lights and their selection"): lum(Le)
 * times the area, in double; 0 for a primitive whose material does not emit. */
static double triangle_emitter_weight(const struct scene *scene, int i)
{
	const struct scene_triangle *t = &scene->triangles[i];
	const struct scene_material *m = &scene->materials[t->material];
	double e1[3], e2[3], c[3];

	for (int k = 0; k < 3; k++) {
		e1[k] = t->v[1][k] - t->v[0][k];
		e2[k] = t->v[2][k] - t->v[0][k];
	}
	vec3_cross(e1, e2, c);
	return scene_material_emits(m) ? luminance(m->emission) * 0.5 * vec3_length(c) : 0;
}

static double sphere_emitter_weight(const struct scene *scene, int i)
{
	const struct scene_sphere *sp = &scene->spheres[i];
	const struct scene_material *m = &scene->materials[sp->material];

	return scene_material_emits(m) ? luminance(m->emission) * 4 * M_PI * sp->radius * sp->radius
				       : 0;
}

/* Fills emitters[] in their order (the emissive triangles, then the
 * emissive spheres, each in scene order), each cdf the sum of the weights
 * up to and with it over total (rounded to float; the last 1), and returns
 * the sum of the weights. With total 0 only the sum is taken. */
static double fill_emitters(struct rt_emitter *emitters, const struct scene *scene,
			    const int *device_sphere, double total)
{
	double sum = 0;
	int n = 0, count = emitter_count(scene);

	for (int i = 0; i < scene->triangle_count + scene->sphere_count; i++) {
		int sphere = i >= scene->triangle_count, index = i - (sphere ? scene->triangle_count : 0);
		if (!scene_material_emits(
			    &scene->materials[sphere ? scene->spheres[index].material
						     : scene->triangles[index].material]))
			continue;
		sum += sphere ? sphere_emitter_weight(scene, index)
			      : triangle_emitter_weight(scene, index);
		if (total > 0) {
			emitters[n].prim = sphere ? (RT_PRIM_SPHERE << RT_PRIM_KIND_SHIFT) |
							    (rt_uint)device_sphere[index]
						  : (RT_PRIM_TRIANGLE << RT_PRIM_KIND_SHIFT) |
							    (rt_uint)index;
			emitters[n].cdf = n == count - 1 ? 1.0f : (float)(sum / total);
		}
		n++;
	}
	return sum;
}

/* The environment map (RENDERING.md, "The environment"): its texels with
 * the scale applied, and the cumulative distributions that sample it by
 * weight, lum(texel) sin(theta at the row's centre), computed in double. */
/* Texel (j, k)'s radiance with the scale, and its weight. */
static double env_texel(const struct scene_environment *env, int j, int k, double rgb[3])
{
	const float *in = env->rgb + 3 * ((size_t)k * env->width + j);

	for (int c = 0; c < 3; c++)
		rgb[c] = in[c] * env->scale;
	return luminance(rgb) * sin(M_PI * (k + 0.5) / env->height);
}

static double env_row_weight(const struct scene_environment *env, int k)
{
	double rgb[3], row = 0;

	for (int j = 0; j < env->width; j++)
		row += env_texel(env, j, k, rgb);
	return row;
}

void scene_block_env_rows(const struct scene_environment *env, int k0, int k1, void *texels,
			  float *column_cdf)
{
	rt_vec4 *out = texels;
	int w = env->width;

	for (int k = k0; k < k1; k++) {
		double row = env_row_weight(env, k), sum = 0, rgb[3];
		for (int j = 0; j < w; j++) {
			size_t t = (size_t)(k - k0) * w + j;
			sum += env_texel(env, j, k, rgb);
			out[t] = vec4(rgb, 0.0);
			column_cdf[t] = j == w - 1 ? 1.0f
				       : row > 0   ? (float)(sum / row)
						   : (float)((j + 1.0) / w);
		}
	}
}

/* The map's header fields and row CDF; with texels, its texels and column
 * CDFs too. */
static void pack_environment(unsigned char *block, struct rt_path *path, const struct layout *l,
			     const struct scene_environment *env, int texels)
{
	float *row_cdf = (float *)(block + l->env_row_cdf);
	int w = env->width, h = env->height;
	double total = 0, rows = 0;

	path->environment = RT_ENVIRONMENT_MAP;
	path->env_width = w;
	path->env_height = h;
	path->env_texel_offset = (rt_uint)l->env_texel;
	path->env_row_cdf_offset = (rt_uint)l->env_row_cdf;
	path->env_column_cdf_offset = (rt_uint)l->env_column_cdf;
	path->env_cos = (float)cos(env->rotate * M_PI / 180);
	path->env_sin = (float)sin(env->rotate * M_PI / 180);
	for (int k = 0; k < h; k++)
		total += env_row_weight(env, k);
	for (int k = 0; k < h; k++) {
		rows += env_row_weight(env, k);
		row_cdf[k] = k == h - 1 ? 1.0f : total > 0 ? (float)(rows / total) : 0.0f;
	}
	if (texels)
		scene_block_env_rows(env, 0, h, block + l->env_texel,
				     (float *)(block + l->env_column_cdf));
	path->env_inv_weight = total > 0 ? (float)(1.0 / total) : 0.0f;
	path->env_is_light = total > 0;
}

/* The path integrator's header, BSDFs and emitters. device_sphere[i]:
 * scene sphere i's index on the device. */
static void pack_path(unsigned char *block, struct rt_scene *header, const struct layout *l,
		      const struct scene *scene, const int *device_sphere, int texels)
{
	struct rt_path *path = (struct rt_path *)(block + l->path);
	struct rt_bsdf *bsdfs = (struct rt_bsdf *)(block + l->bsdf);
	struct rt_emitter *emitters = (struct rt_emitter *)(block + l->emitter);
	int count = emitter_count(scene);
	double total;

	header->path_offset = (rt_uint)l->path;
	path->bsdf_offset = (rt_uint)l->bsdf;
	path->emitter_offset = (rt_uint)l->emitter;
	for (int i = 0; i < scene->material_count; i++)
		pack_bsdf(&bsdfs[i], &scene->materials[i]);
	total = fill_emitters(emitters, scene, device_sphere, 0);
	if (total > 0)
		fill_emitters(emitters, scene, device_sphere, total);
	else
		count = 0; /* emission too faint for a double's luminance: none */
	path->emitter_count = count;
	path->inv_emitter_weight = count ? (float)(1.0 / total) : 0.0f;
	path->environment = scene->background[0] > 0 || scene->background[1] > 0 ||
					    scene->background[2] > 0
				    ? RT_ENVIRONMENT_UNIFORM
				    : RT_ENVIRONMENT_NONE;
	path->env_is_light = path->environment != RT_ENVIRONMENT_NONE;
	if (scene->environment.rgb)
		pack_environment(block, path, l, &scene->environment, texels);
	path->group_count = scene->light_count + (count > 0) + path->env_is_light;
}

/* The textures' arrays (RENDERING.md, "Textures"): the vertices' texture
 * coordinates, what each material takes from textures, each texture's
 * header and, with texels, its texels, and the decode table of 8-bit
 * texels. */
static void pack_textures(unsigned char *block, struct rt_scene *header, const struct layout *l,
			  const struct scene *scene, const struct mesh_block *mesh, int texels)
{
	struct rt_material_map *maps = (struct rt_material_map *)(block + l->material_map);
	struct rt_texture *textures = (struct rt_texture *)(block + l->texture);
	float *table = (float *)(block + l->texture_table);
	size_t texel = l->texel;

	header->texture_count = scene->texture_count;
	if (mesh->uvs)
		memcpy(block + l->uv, mesh->uvs,
		       (size_t)mesh->vertex_count * sizeof(struct rt_vertex_uv));
	for (int i = 0; i < scene->material_count; i++) {
		const struct scene_material *m = &scene->materials[i];
		maps[i].texture = m->texture - 1;
		maps[i].alpha_texture = m->alpha_texture - 1;
		maps[i].alpha_cutoff = (float)m->alpha_cutoff;
		maps[i].alpha_scale = (float)m->alpha_scale;
	}
	for (int i = 0; i < scene->texture_count; i++) {
		const struct scene_texture *t = &scene->textures[i];
		textures[i].offset = (rt_uint)texel;
		textures[i].width = t->width;
		textures[i].height = t->height;
		textures[i].flags = (rt_uint)t->wrap_s | (rt_uint)t->wrap_t << RT_WRAP_T_SHIFT |
				    (t->is_float ? RT_TEXTURE_FLOAT : 0u) |
				    (t->is_linear ? RT_TEXTURE_LINEAR : 0u);
		if (texels && t->bytes)
			memcpy(block + texel, t->texels, t->bytes);
		texel += round16(t->bytes);
	}
	/* Computed in double, rounded once to float. */
	for (int i = 0; i < 256; i++) {
		double x = i / 255.0;
		table[i] = (float)(x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4));
		table[256 + i] = (float)x;
	}
}

size_t scene_block_bytes(const struct scene *scene, const struct mesh_block *mesh, const struct bvh *bvh)
{
	return layout_of(scene, mesh, bvh).total;
}

size_t scene_block_head_bytes(const void *block)
{
	const struct rt_scene *header = block;
	const struct rt_texture *textures =
		(const struct rt_texture *)((const unsigned char *)block + header->texture_offset);
	const struct rt_path *path =
		(const struct rt_path *)((const unsigned char *)block + header->path_offset);

	if (header->path_offset && path->environment == RT_ENVIRONMENT_MAP)
		return path->env_texel_offset;
	return header->texture_count ? textures[0].offset : header->total_bytes;
}

/* scene_block_pack, and scene_block_pack_head without texels. */
static void *pack(const struct scene *scene, const struct mesh_block *mesh, const struct bvh *bvh,
		  int width, int height, int max_depth, int texels, size_t *bytes)
{
	struct layout l = layout_of(scene, mesh, bvh);
	size_t material_offset = l.material, sphere_offset = l.sphere, plane_offset = l.plane;
	size_t light_offset = l.light, total = l.total;
	int sphere_slots = l.sphere_slots;
	unsigned char *block;

	/* The header's offsets are 32-bit (block_prepare_scene refuses more). */
	if (total > DEVSCENE_MAX_BYTES)
		return NULL;
	block = calloc(1, texels ? total : l.head);
	if (!block)
		return NULL;

	struct rt_scene *header = (struct rt_scene *)block;
	pack_camera(header, scene, width, height);
	header->background = vec4(scene->background, 0.0);
	header->ambient = vec4(scene->ambient, 0.0);
	header->width = width;
	header->height = height;
	header->max_depth = max_depth;
	header->material_count = scene->material_count;
	header->sphere_count = scene->sphere_count;
	header->sphere_slots = sphere_slots;
	header->plane_count = scene->plane_count;
	header->light_count = scene->light_count;
	header->material_offset = (rt_uint)material_offset;
	header->sphere_offset = (rt_uint)sphere_offset;
	header->plane_offset = (rt_uint)plane_offset;
	header->light_offset = (rt_uint)light_offset;
	header->total_bytes = (rt_uint)total;
	header->triangle_offset = (rt_uint)l.triangle;
	header->vertex_offset = (rt_uint)l.vertex;
	header->normal_offset = (rt_uint)l.normal;
	header->triangle_count = scene->triangle_count;
	header->bvh_node_offset = (rt_uint)l.node;
	header->bvh_ref_offset = (rt_uint)l.ref;
	header->bvh_triangle_offset = (rt_uint)l.leaf_triangle;
	/* Where the textures' arrays are, also empty ones: the leaf triangles end there. */
	header->uv_offset = (rt_uint)l.uv;
	header->material_map_offset = (rt_uint)l.material_map;
	header->texture_offset = (rt_uint)l.texture;
	header->texture_table_offset = (rt_uint)l.texture_table;
	int *order = sphere_order(scene, bvh);
	if (!order || pack_bvh(block, header, bvh, mesh)) {
		free(order);
		free(block);
		return NULL;
	}

	struct rt_material *materials = (struct rt_material *)(block + material_offset);
	for (int i = 0; i < scene->material_count; i++)
		pack_material(&materials[i], &scene->materials[i]);

	struct rt_sphere *spheres = (struct rt_sphere *)(block + sphere_offset);
	for (int i = 0; i < scene->sphere_count; i++)
		pack_sphere(&spheres[i], scene, &scene->spheres[order[i]], order[i]);
	if (scene->integrator == SCENE_INTEGRATOR_PATH) {
		int *device_sphere = malloc((size_t)(scene->sphere_count + 1) * sizeof(int));
		if (!device_sphere) {
			free(order);
			free(block);
			return NULL;
		}
		for (int i = 0; i < scene->sphere_count; i++)
			device_sphere[order[i]] = i;
		pack_path(block, header, &l, scene, device_sphere, texels);
		free(device_sphere);
	}
	free(order);
	/* The padding: radius² -1, which no squared distance is below. */
	for (int i = scene->sphere_count; i < sphere_slots; i++)
		spheres[i].center.s[3] = -1.0f;

	struct rt_plane *planes = (struct rt_plane *)(block + plane_offset);
	for (int i = 0; i < scene->plane_count; i++)
		pack_plane(&planes[i], scene, &scene->planes[i]);

	struct rt_light *lights = (struct rt_light *)(block + light_offset);
	for (int i = 0; i < scene->light_count; i++)
		pack_light(&lights[i], scene, &scene->lights[i]);

	if (scene->triangle_count > 0) { /* else the arrays are NULL, which memcpy may not take */
		memcpy(block + l.triangle, mesh->triangles,
		       (size_t)scene->triangle_count * sizeof(struct rt_triangle));
		memcpy(block + l.vertex, mesh->vertices,
		       (size_t)mesh->vertex_count * sizeof(struct rt_vertex));
		memcpy(block + l.normal, mesh->normals,
		       (size_t)mesh->vertex_count * sizeof(struct rt_vertex_normal));
	}
	if (scene_has_textures(scene))
		pack_textures(block, header, &l, scene, mesh, texels);

	*bytes = total;
	return block;
}

void *scene_block_pack(const struct scene *scene, const struct mesh_block *mesh,
		       const struct bvh *bvh, int width, int height, int max_depth, size_t *bytes)
{
	return pack(scene, mesh, bvh, width, height, max_depth, 1, bytes);
}

void *scene_block_pack_head(const struct scene *scene, const struct mesh_block *mesh,
			    const struct bvh *bvh, int width, int height, int max_depth,
			    size_t *bytes)
{
	return pack(scene, mesh, bvh, width, height, max_depth, 0, bytes);
}

/* The float step at distance d from the eye: the spacing of floats there. */
static double float_step(double d)
{
	float f = (float)d;

	return (double)nextafterf(f, FLT_MAX) - (double)f;
}

/* Whether an object (named by what) of the given size at distance d from
 * the eye spans fewer than DEVSCENE_MIN_STEPS float steps; then the message. */
static int too_small(const struct scene *scene, const char *what, double size, double d, char *err,
		     size_t err_size)
{
	double step = float_step(d);

	if (size >= DEVSCENE_MIN_STEPS * step)
		return 0;
	snprintf(err, err_size,
		 "%s: %s %g at %g from the eye is below what float resolves there (%d steps "
		 "of %g): rtcl renders in float relative to the eye; move the camera closer "
		 "or enlarge the object",
		 quote_text(scene->source), what, size, d, DEVSCENE_MIN_STEPS, step);
	return 1;
}

int scene_block_check_resolution(const struct scene *scene, char *err, size_t err_size)
{
	char what[128];

	for (int i = 0; i < scene->sphere_count; i++) {
		double c[3];
		scene_from_eye(scene, scene->spheres[i].center, c);
		snprintf(what, sizeof(what), "spheres[%d]: the radius", i);
		if (too_small(scene, what, scene->spheres[i].radius, vec3_length(c), err, err_size))
			return -1;
	}
	for (int i = 0; i < scene->triangle_count; i++) {
		const struct scene_triangle *t = &scene->triangles[i];
		double v[3][3], edge = 0, nearest = HUGE_VAL;
		for (int k = 0; k < 3; k++) {
			scene_from_eye(scene, t->v[k], v[k]);
			nearest = fmin(nearest, vec3_length(v[k]));
		}
		for (int k = 0; k < 3; k++) {
			double e[3] = {v[(k + 1) % 3][0] - v[k][0], v[(k + 1) % 3][1] - v[k][1],
				       v[(k + 1) % 3][2] - v[k][2]};
			edge = fmax(edge, vec3_length(e));
		}
		snprintf(what, sizeof(what),
			 "triangle %d (of the meshes', then the inline ones): the longest edge", i);
		if (too_small(scene, what, edge, nearest, err, err_size))
			return -1;
	}
	return 0;
}
