// Stands in for Node's fs and path in the browser bundle: draco3d's decoder script requires them
// only on its Node code path.
export default {};
