// Example surfaces for the gallery menu: the thesis's test functions first, then classics.
// Each gives the equation as a GeoGebra user types it, parameter values and the view box.

const cube = (r) => [-r, r, -r, r, -r, r];

export const GALLERY = [
  {
    name: 'Bumpy sphere (thesis)',
    expression: 'x^2+y^2+z^2+2cos(2x)=5',
    box: cube(3),
  },
  {
    name: 'Ellipsoid (thesis)',
    expression: '10x^2+y^2+z^2=20',
    box: cube(5),
  },
  {
    name: 'Blobby cube (thesis, fig. 4.1)',
    expression: 'sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20',
    box: cube(28),
  },
  {
    name: 'Sphere with radius² a',
    expression: 'x^2+y^2+z^2=a',
    parameters: { a: 4 },
    box: cube(3),
  },
  {
    name: 'Torus',
    expression: '(sqrt(x^2+y^2)-R)^2+z^2=r^2',
    parameters: { R: 2, r: 0.7 },
    box: [-3.2, 3.2, -3.2, 3.2, -1.2, 1.2],
  },
  {
    name: 'Tanglecube',
    expression: 'x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0',
    box: cube(3),
  },
  {
    name: 'Gyroid',
    expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=t',
    parameters: { t: 0 },
    box: cube(6),
  },
  {
    name: 'Schwarz P surface',
    expression: 'cos(x)+cos(y)+cos(z)=0',
    box: cube(6),
  },
  {
    name: "Kummer-like quartic",
    expression: 'x^4+y^4+z^4-(x^2+y^2+z^2)=-k',
    parameters: { k: 0.2 },
    box: cube(1.5),
  },
  {
    name: 'Heart',
    expression: '(x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=0',
    box: [-1.5, 1.5, -1.5, 1.5, -1.5, 1.5],
  },
  {
    name: 'Hyperboloid of one sheet',
    expression: 'x^2+y^2-z^2=c',
    parameters: { c: 1 },
    box: cube(3),
  },
  {
    name: 'Genus-2 surface',
    expression: '((x^2+y^2)^2-x^2+y^2)^2+z^2=0.01',
    box: [-1.4, 1.4, -0.9, 0.9, -0.3, 0.3],
  },
];
