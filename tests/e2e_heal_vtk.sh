#!/usr/bin/env bash
# The heal fields open in VTK's own XML reader (what ParaView uses): extents,
# spacing, every field as cell data with the right length. Skipped (exit 77)
# where VTK's Python module is not installed (Debian: python3-vtk9).
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
PY=/usr/bin/python3
"$PY" -c "import vtk" 2>/dev/null || { echo "python3-vtk9 not installed: skipped"; exit 77; }
"$CLI" heal --grid 24x20x8 --days 2 --snapshot-every 1 --out "$T/h" --quiet || exit 1
"$PY" - "$T/h/fields" <<'PY'
import glob, sys, vtk, xml.etree.ElementTree as ET
d = sys.argv[1]
files = sorted(glob.glob(d + '/fields_*.vti'))
assert len(files) >= 3, files
pvd = ET.parse(d + '/fields.pvd').getroot()
times = [float(e.get('timestep')) for e in pvd.iter('DataSet')]
assert times == sorted(times) and len(times) == len(files), times
names = {'cell_state', 'oxygen', 'mdgf', 'capillary', 'fibroblast', 'eschar', 'epithelium', 'scar', 'plasma'}
for f in files:
    r = vtk.vtkXMLImageDataReader()
    r.SetFileName(f)
    r.Update()
    img = r.GetOutput()
    assert img.GetDimensions() == (25, 21, 9), img.GetDimensions()
    cd = img.GetCellData()
    got = {cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())}
    assert names <= got, got
    for n in names:
        a = cd.GetArray(n)
        assert a.GetNumberOfTuples() == 24 * 20 * 8
        lo, hi = a.GetRange()
        assert lo >= 0 and hi < 1e6, (n, lo, hi)
print("1 passed, 0 failed")
PY
