# Geometry-only YADE 2023.02a script: head-on collisions, one per impact speed, side by side
# along x (pairs of spheres, or spheres on the wall z = 0). The exported snippet's block 1 goes
# in verbatim before the bodies and its block 2 (if any) after them; tests/test_dem_programs.py
# fills in GEOMETRY, SPEEDS, RADIUS2 and DURATION.
GEOMETRY = "@GEOMETRY@"
SPEEDS = [@SPEEDS@]
RADIUS2 = @RADIUS2@  # the second sphere's radius (pairs); None: equal to ehd_radius
@BLOCK1@
DURATION = @DURATION@  # after block 1: in units of its ehd_dt_max
r1 = ehd_radius
r2 = r1 if RADIUS2 is None else RADIUS2
pairs = []
for k, v in enumerate(SPEEDS):
    x = 4.0 * (r1 + r2) * k
    gap = 0.05 * r1
    if GEOMETRY == "sphere-wall":
        a = O.bodies.append(sphere((x, 0, r1 + gap), r1, material=ehd_mat))
        O.bodies[a].state.vel = Vector3(0, 0, -v)
        pairs.append((a, None, v))
    else:
        a = O.bodies.append(sphere((x, 0, -r1 - gap / 2), r1, material=ehd_mat))
        b = O.bodies.append(sphere((x, 0, r2 + gap / 2), r2,
                                   material=globals().get("ehd_mat2", ehd_mat)))
        O.bodies[a].state.vel = Vector3(0, 0, v / 2)
        O.bodies[b].state.vel = Vector3(0, 0, -v / 2)
        pairs.append((a, b, v))
if GEOMETRY == "sphere-wall":
    O.bodies.append(wall(0.0, axis=2, sense=1, material=ehd_wall_mat))
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_ViscElMat_ViscElMat_ViscElPhys()], [Law2_ScGeom_ViscElPhys_Basic()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, 0)),
]
@BLOCK2@
O.dt = ehd_dt_max
O.run(int(math.ceil(DURATION / O.dt)), True)
for a, b, v in pairs:
    va = O.bodies[a].state.vel[2]
    if b is None:
        gap_end = O.bodies[a].state.pos[2] - r1
        print("EHD_RESULT", v, va / v, gap_end)
    else:
        vb = O.bodies[b].state.vel[2]
        gap_end = O.bodies[b].state.pos[2] - O.bodies[a].state.pos[2] - r1 - r2
        print("EHD_RESULT", v, (vb - va) / v, gap_end)
