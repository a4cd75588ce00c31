"""ParaView reader for isowave's .isw files (issue #50; docs/PARAVIEW.md).

Load it by running this file in ParaView's Python (View > Python Shell > Run Script, or
`pvpython isowave_reader.py`): it loads itself as a plugin, after which File > Open reads .isw files.
Tools > Manage Plugins > Load New also works, but not on Debian 12's ParaView 5.11, whose plugin
loader needs inspect.getargspec (gone in Python 3.11) before it reads this file; running the file
first provides it. It decodes with the isowave Python module, which must import in ParaView's
interpreter (cmake --install puts it there for Debian's python3).

Properties, as `isowave decode` takes them: the stream prefix (Bytes, or MaxError in cells from the
file's rate table; 0: the whole file), Percent of full resolution, Level (-1: the finest) and
LimitSurface. Point arrays to colour by: "level", the level each vertex first appears on (0: the
base mesh), and "detail", the magnitude of the decoded wavelet coefficient at each vertex (world
units). Field data: "bytes_read" and "file_bytes".
"""
import inspect

if not hasattr(inspect, "getargspec"):  # ParaView 5.11's plugin loader on Python 3.11 (Debian 12)
    inspect.getargspec = inspect.getfullargspec

import numpy as np
from paraview.util.vtkAlgorithm import VTKPythonAlgorithmBase, smdomain, smhint, smproperty, smproxy
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData


def polydata(decoded):
    """vtkPolyData of isowave.decode_polygons()'s dict."""
    out = vtkPolyData()
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(decoded["vertices"], deep=True))
    out.SetPoints(points)
    cells = vtkCellArray()
    cells.SetData(numpy_support.numpy_to_vtkIdTypeArray(decoded["offsets"].astype(np.int64), deep=True),
                  numpy_support.numpy_to_vtkIdTypeArray(decoded["corners"].astype(np.int64), deep=True))
    out.SetPolys(cells)
    wrapped = dsa.WrapDataObject(out)
    wrapped.PointData.append(decoded["level"], "level")
    wrapped.PointData.append(decoded["detail"], "detail")
    wrapped.FieldData.append(np.array([decoded["bytes_read"]], dtype=np.int64), "bytes_read")
    wrapped.FieldData.append(np.array([decoded["file_bytes"]], dtype=np.int64), "file_bytes")
    return out


@smproxy.reader(name="IsowaveReader", label="isowave wavelet surface", extensions="isw",
                file_description="isowave files")
class IsowaveReader(VTKPythonAlgorithmBase):
    def __init__(self):
        VTKPythonAlgorithmBase.__init__(self, nInputPorts=0, nOutputPorts=1, outputType="vtkPolyData")
        self._path = None
        self._bytes = 0
        self._max_error = 0.0
        self._percent = 100.0
        self._level = -1
        self._limit = False

    def _set(self, name, value):
        if getattr(self, name) != value:
            setattr(self, name, value)
            self.Modified()

    @smproperty.stringvector(name="FileName")
    @smdomain.filelist()
    @smhint.filechooser(extensions="isw", file_description="isowave files")
    def SetFileName(self, path):
        self._set("_path", path)

    @smproperty.intvector(name="Bytes", default_values=0)
    @smdomain.intrange(min=0)
    def SetBytes(self, count):
        """Read only the file's first bytes (0: all of them)."""
        self._set("_bytes", int(count))

    @smproperty.doublevector(name="MaxError", default_values=0.0)
    @smdomain.doublerange(min=0.0)
    def SetMaxError(self, cells):
        """Read the shortest prefix whose recorded error is within this many cells (0: none)."""
        self._set("_max_error", float(cells))

    @smproperty.doublevector(name="Percent", default_values=100.0)
    @smdomain.doublerange(min=0.0, max=100.0)
    def SetPercent(self, percent):
        self._set("_percent", float(percent))

    @smproperty.intvector(name="Level", default_values=-1)
    @smdomain.intrange(min=-1, max=10)
    def SetLevel(self, level):
        """The control mesh of this level (-1: the finest)."""
        self._set("_level", int(level))

    @smproperty.xml("""<IntVectorProperty name="LimitSurface" command="SetLimitSurface" number_of_elements="1"
                          default_values="0"><BooleanDomain name="bool"/></IntVectorProperty>""")
    def SetLimitSurface(self, limit):
        self._set("_limit", bool(limit))

    def options(self):
        """The keyword arguments of isowave.decode_polygons() the properties give."""
        return {
            "bytes": self._bytes if self._bytes > 0 else None,
            "max_error": self._max_error if self._max_error > 0 else None,
            "percent": self._percent if self._percent < 100 else None,
            "level": self._level if self._level >= 0 else None,
            "limit": self._limit,
        }

    def RequestData(self, request, in_info, out_info):
        import isowave  # here, so that the plugin loads (and says why it cannot decode) without the module
        try:
            if not self._path:
                raise ValueError("no file name")
            decoded = isowave.decode_polygons(self._path, **self.options())
        except (isowave.Error, ValueError, TypeError, OSError) as error:
            vtkOutputWindow.GetInstance().DisplayErrorText("IsowaveReader: %s" % error)
            return 0
        vtkPolyData.GetData(out_info, 0).ShallowCopy(polydata(decoded))
        return 1


if __name__ == "__main__":  # run as a script: load this file as a plugin
    from paraview.simple import LoadPlugin

    LoadPlugin(__file__, remote=False, ns=globals())
