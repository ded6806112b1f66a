// What the server found out about a surface, in words for someone who types equations in GeoGebra
// or Desmos rather than reads protocols. The server proves the shape (its pieces, holes and
// bubbles) cell by cell before refining it (PROTOCOL.md 3.4), and says so in `progress`
// (`resolving`) and `converged` (`outcome`, `budget_unreachable`, `certified`,
// `unresolved_cells`). Pure: no DOM.

export const NO_SURFACE_MESSAGE =
  'No surface in the view box: the equation has no solution there. Check the values (a negative radius² has no sphere) or enlarge the box.';
export const REGION_MESSAGE =
  'Not a surface: the equation holds on a whole region of the view box, not on a thin sheet (as floor(x)=0 holds for every x from 0 to 1), so there is nothing to draw.';
export const UNCERTAIN_TITLE =
  'Near a few spots (such as the tip of a cone or a sharp crease) the shape could not be proven exactly; there it is drawn as a close guess.';

/**
 * The message for a surface whose session the server ended on purpose (`closed` with `reason`):
 * `expired` after its idle time without a change (an hour by default), `closed` by another client.
 */
export function endedMessage(reason) {
  const why = reason === 'expired' ? 'after a long time without a change' : `(${reason})`;
  return `The server ended this surface's session ${why}. Press Enter or change a value to draw it again.`;
}

/** The message for a surface whose shape needs more triangles than the budget allows. */
export function budgetMessage(triangles, budget) {
  return `This shape needs at least ${triangles} triangles (for all its pieces and holes), more than the maximum of ${budget}: it is shown with ${triangles}.`;
}

/**
 * The notes a converged version calls for: [] for an ordinary surface.
 * @param {object|null} converged the server's `converged` message of the shown version
 * @param {number} held the triangles the viewer holds for it (what it shows and counts)
 * @param {number} budget the budget in force
 */
export function outcomeNotes(converged, held, budget) {
  if (!converged) return [];
  if (converged.outcome === 'no_surface') return [NO_SURFACE_MESSAGE];
  if (converged.outcome === 'region_not_surface') return [REGION_MESSAGE];
  // Any other outcome reads as "surface" (PROTOCOL.md 3.4). The count said is the one held.
  if (converged.budget_unreachable) return [budgetMessage(held, budget)];
  return [];
}

/** True when a converged surface is drawn without a proof of its shape at some spots. */
export function uncertain(converged) {
  return Boolean(converged && converged.certified === false && converged.unresolved_cells > 0 && converged.outcome !== 'region_not_surface');
}
