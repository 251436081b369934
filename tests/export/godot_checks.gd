# Run by test_engines.py in headless Godot 3: VF_TRES=a.tres VF_OUT=out.json godot3-server --path DIR -s godot_checks.gd
# Loads the Animation resource, plays it with an AnimationPlayer on a MeshInstance whose mesh has one blend
# shape per track (named from the tracks' paths), and writes the blend-shape weights at VF_TIMES as JSON.
extends SceneTree

func _init():
	var anim = load(OS.get_environment("VF_TRES"))
	var out = {"tracks": anim.get_track_count(), "length": anim.length, "step": anim.step, "paths": [],
		"keys": [], "played": []}
	var names = []
	for i in range(anim.get_track_count()):
		var path = str(anim.track_get_path(i))
		out["paths"].append(path)
		out["keys"].append(anim.track_get_key_count(i))
		names.append(path.split("blend_shapes/")[1])
	var verts = PoolVector3Array([Vector3(0, 0, 0), Vector3(1, 0, 0), Vector3(0, 1, 0)])
	var arrays = []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = verts
	var shapes = []
	var mesh = ArrayMesh.new()
	for n in names:
		mesh.add_blend_shape(n)
		var b = []
		b.resize(Mesh.ARRAY_MAX)
		b[Mesh.ARRAY_VERTEX] = verts
		shapes.append(b)
	mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays, shapes)
	var face = MeshInstance.new()
	face.mesh = mesh
	root.add_child(face)
	var player = AnimationPlayer.new()
	face.add_child(player)
	player.add_animation("speech", anim)
	player.play("speech")
	for t in parse_json(OS.get_environment("VF_TIMES")):
		player.seek(t, true)
		var row = []
		for n in names:
			row.append(face.get("blend_shapes/" + n))
		out["played"].append(row)
	var f = File.new()
	f.open(OS.get_environment("VF_OUT"), File.WRITE)
	f.store_string(to_json(out))
	f.close()
	quit()
