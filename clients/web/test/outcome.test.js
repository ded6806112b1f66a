import assert from 'node:assert/strict';
import { test } from 'node:test';

import { NO_SURFACE_MESSAGE, REGION_MESSAGE, budgetMessage, endedMessage, outcomeNotes, uncertain } from '../src/outcome.js';

const converged = (fields) => ({ type: 'converged', version: 1, triangles: 120, outcome: 'surface', certified: true, unresolved_cells: 0, budget_unreachable: false, ...fields });

test('outcomeNotes: no surface, a region, a budget below the shape, or nothing to say', () => {
  assert.deepEqual(outcomeNotes(null, 0, 100), [], 'not converged: nothing known yet');
  assert.deepEqual(outcomeNotes(converged({}), 120, 20000), []);
  assert.deepEqual(outcomeNotes(converged({ outcome: 'no_surface', triangles: 0 }), 0, 20000), [NO_SURFACE_MESSAGE]);
  assert.deepEqual(outcomeNotes(converged({ outcome: 'region_not_surface', triangles: 0 }), 0, 20000), [REGION_MESSAGE]);
  assert.deepEqual(outcomeNotes(converged({ outcome: 'a_later_outcome' }), 120, 20000), [], 'an unknown outcome reads as surface');
});

test('outcomeNotes: an unreachable budget names the count the viewer holds', () => {
  const [note] = outcomeNotes(converged({ budget_unreachable: true, triangles: 212 }), 212, 100);
  assert.equal(note, budgetMessage(212, 100));
  assert.match(note, /needs at least 212 triangles/);
  assert.match(note, /maximum of 100/);
});

test('uncertain: a converged surface with cells left without proof', () => {
  assert.equal(uncertain(null), false);
  assert.equal(uncertain(converged({})), false);
  assert.equal(uncertain(converged({ certified: false, unresolved_cells: 3 })), true, "a cone's apex");
  assert.equal(uncertain(converged({ certified: false, unresolved_cells: 0 })), false);
  assert.equal(uncertain(converged({ outcome: 'region_not_surface', certified: false, unresolved_cells: 9 })), false, 'the region message says it all');
});

test('endedMessage: an expired session in plain words, another reason named', () => {
  assert.match(endedMessage('expired'), /ended this surface's session after a long time without a change\. Press Enter/);
  assert.match(endedMessage('closed'), /session \(closed\)\. Press Enter/);
});
