#!/usr/bin/python3
"""Renders the last frame of a pdyn vtk output (.pvd) to a PNG: the springs
as lines coloured by speed, the obstacles (part 1) in grey. The files are
read with VTK's own reader (python3-vtk9). With a display, VTK renders the
picture itself (offscreen); Debian's VTK 9.1 renders through X only, so on
a machine without one the same polydata are drawn with matplotlib instead
(python3-matplotlib).

    python3 scripts/render_vtk.py out/run.pvd picture.png [WIDTH HEIGHT]
"""
import os
import sys
import xml.etree.ElementTree as ET

import vtk


def read(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def matplotlib_picture(parts, png, w, h, last):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import cm
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection
    from vtkmodules.util.numpy_support import vtk_to_numpy

    fig = plt.figure(figsize=(w / 100, h / 100), dpi=100)
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    # Obstacles first, the cloth over them: matplotlib does not sort depth
    # across collections.
    for part, poly in sorted(parts, key=lambda p: p[0] != "1"):
        pts = vtk_to_numpy(poly.GetPoints().GetData())
        if part == "1":
            polys = poly.GetPolys()
            conn = vtk_to_numpy(polys.GetConnectivityArray())
            offs = vtk_to_numpy(polys.GetOffsetsArray())
            faces = [pts[conn[offs[k]:offs[k + 1]]] for k in range(len(offs) - 1)]
            ax.add_collection3d(Poly3DCollection(faces, facecolor=(0.72, 0.72, 0.76, 0.35),
                                                 edgecolor=(0.55, 0.55, 0.6, 0.25), linewidth=0.2,
                                                 zorder=1))
            continue
        v = vtk_to_numpy(poly.GetPointData().GetArray("velocity"))
        speed = (v ** 2).sum(axis=1) ** 0.5
        lines = poly.GetLines()
        conn = vtk_to_numpy(lines.GetConnectivityArray()).reshape(-1, 2)
        segs = pts[conn]
        s = speed[conn].mean(axis=1)
        colors = cm.viridis(s / max(s.max(), 1e-12))
        ax.add_collection3d(Line3DCollection(segs, colors=colors, linewidths=0.4, zorder=2))
    ax.set_xlim(-0.45, 0.45)
    ax.set_ylim(-0.45, 0.45)
    ax.set_zlim(0, 0.9)
    ax.set_box_aspect((0.9, 0.9, 0.9))
    ax.view_init(elev=22, azim=-55)
    ax.set_axis_off()
    fig.tight_layout(pad=0)
    fig.savefig(png, dpi=100)
    print(f"{png}: frame t = {last} s, drawn with matplotlib (no display for VTK), {w} x {h}")


def main():
    pvd, png = sys.argv[1], sys.argv[2]
    w, h = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (800, 600)
    entries = [(float(d.get("timestep")), d.get("part"), d.get("file"))
               for d in ET.parse(pvd).getroot().iter("DataSet")]
    last = max(t for t, _, _ in entries)
    folder = os.path.dirname(pvd)
    if not os.environ.get("DISPLAY"):
        parts = [(part, read(os.path.join(folder, file)))
                 for t, part, file in entries if t == last]
        matplotlib_picture(parts, png, w, h, last)
        return
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1, 1, 1)
    for t, part, file in entries:
        if t != last:
            continue
        poly = read(os.path.join(folder, file))
        mapper = vtk.vtkPolyDataMapper()
        actor = vtk.vtkActor()
        if part == "0":
            speed = vtk.vtkArrayCalculator()
            speed.SetInputData(poly)
            speed.AddVectorArrayName("velocity")
            speed.SetFunction("mag(velocity)")
            speed.SetResultArrayName("speed")
            speed.Update()
            mapper.SetInputConnection(speed.GetOutputPort())
            mapper.SetScalarModeToUsePointFieldData()
            mapper.SelectColorArray("speed")
            mapper.SetScalarRange(speed.GetOutput().GetPointData().GetArray("speed").GetRange())
            lut = vtk.vtkLookupTable()
            lut.SetHueRange(0.66, 0.0)
            lut.Build()
            mapper.SetLookupTable(lut)
            actor.GetProperty().SetLineWidth(1.5)
            actor.GetProperty().SetPointSize(2)
        else:
            mapper.SetInputData(poly)
            mapper.ScalarVisibilityOff()
            actor.GetProperty().SetColor(0.75, 0.75, 0.78)
            actor.GetProperty().SetOpacity(0.9)
        actor.SetMapper(mapper)
        renderer.AddActor(actor)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(1.6, -2.2, 1.5)
    camera.SetFocalPoint(0, 0, 0.4)
    camera.SetViewUp(0, 0, 1)
    camera.SetViewAngle(30)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(w, h)
    window.AddRenderer(renderer)
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    out = vtk.vtkPNGWriter()
    out.SetFileName(png)
    out.SetInputConnection(grab.GetOutputPort())
    out.Write()
    print(f"{png}: frame t = {last} s of {pvd}, {w} x {h}")


if __name__ == "__main__":
    main()
