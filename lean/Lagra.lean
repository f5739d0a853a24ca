import Lagra.Basic
import Lagra.Terms
import Lagra.Invariance
