"""A two-material Poisson problem on a triwild mesh, set up from the physical
names alone (README, "Using the mesh in a solver").

    triwild tests/fixtures/model-box.svg --order 2 --cut-outside -o out/model-box.msh
    python examples/two_materials.py out/model-box.msh

Solves -div(k grad u) = 1 on the meshed domain with u = 0 on the physical curve
`boundary`, k = 1 in the surface `box` and k = 10 in `inclusion`, with
scikit-fem (P1 for `--order 1`, P2 for `--order 2`; scikit-fem reads no cubic
triangles). Prints each material's area and the mean of u over it.
"""

import sys

import meshio
import numpy as np
import skfem
from skfem.helpers import dot, grad
from skfem.io.meshio import from_meshio

CONDUCTIVITY = {"box": 1.0, "inclusion": 10.0}


def main(path: str) -> None:
    mesh = from_meshio(meshio.read(path))
    element = {skfem.MeshTri1: skfem.ElementTriP1, skfem.MeshTri2: skfem.ElementTriP2}[
        type(mesh)
    ]()
    basis = skfem.Basis(mesh, element)

    # One conductivity per triangle, from the physical surfaces.
    k = np.zeros(mesh.nelements)
    for name, value in CONDUCTIVITY.items():
        k[mesh.subdomains[name]] = value
    assert (k > 0).all(), "a triangle outside the two materials"
    k = basis.with_element(skfem.ElementTriP0()).interpolate(k)

    @skfem.BilinearForm
    def stiffness(u, v, w):
        return w.k * dot(grad(u), grad(v))

    @skfem.LinearForm
    def load(v, _):
        return v

    a = stiffness.assemble(basis, k=k)
    b = load.assemble(basis)
    # scikit-fem keeps the tags of 2-node lines only: with P2 (3-node lines)
    # `boundary` is not among mesh.boundaries, and the mesh's boundary facets
    # are the same edges (the physical curve holds every one of them).
    facets = (mesh.boundaries or {}).get("boundary", mesh.boundary_facets())
    u = skfem.solve(*skfem.condense(a, b, D=basis.get_dofs(facets)))

    @skfem.Functional
    def integral(w):
        return w.f

    for name in CONDUCTIVITY:
        sub = skfem.Basis(mesh, element, elements=mesh.subdomains[name])
        area = integral.assemble(sub, f=1.0)
        mean = integral.assemble(sub, f=sub.interpolate(u)) / area
        print(f"{name}: area {area:.6f}, mean u {mean:.6f}")
    print(f"max u {u.max():.6f} on {mesh.nelements} triangles ({type(element).__name__})")


if __name__ == "__main__":
    main(sys.argv[1])
