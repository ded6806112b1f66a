// The mesh of an octree's frontier (steps 2 to 6 of phase 1: corner values, crossings, grading
// and Marching Cubes 33 with crack patching, roots, cleanup), made over as many calls as budgets
// need: the work goes in chunks of leaves, crossings or cells, the budget checked between them,
// and what a call leaves undone the next one takes up, so the mesh does not depend on where
// budgets cut it. Polygonizer::mesh_slice (polygonizer.h) is its user.
#pragma once

#include <memory>
#include <vector>

#include "polygonize/evaluator_pool.h"
#include "polygonize/id_tables.h"
#include "polygonize/lattice.h"
#include "polygonize/octree.h"
#include "polygonize/polygonizer.h"
#include "work/work_budget.h"

namespace isomesh {

class FrontierMesher {
  public:
    /// Meshes `frontier` (in octree order), reading and adding corner values in `values`; fills
    /// in the mesh's adjacency at the end when `adjacency` (PolygonizeSettings::adjacency).
    FrontierMesher(EvaluatorPool& workers, const Lattice& lattice, const OctreeSettings& settings,
                   ValueMap& values, std::vector<FrontierCell> frontier, bool adjacency);
    ~FrontierMesher();

    /// Goes on until the mesh is made (true) or the budget is exhausted or cancelled (false).
    bool advance(const WorkBudget& budget);
    /// The mesh. Precondition: advance() returned true.
    PolygonizeResult take();

  private:
    class Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace isomesh
