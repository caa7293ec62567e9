/* The forcing of the peers' Siconos model as a Siconos plugin (benchmarks/peers/siconos_peer.py):
 * the FExt of a LagrangianDS, F_ext,i(t) = g_i f sin(omega t), with z = [f, omega, g_1, ..., g_n]
 * (g_i = T_A,i / T_B,i: the modal force per unit modal mass). Siconos calls it at every evaluation
 * of F_ext (LagrangianDS::computeFExt) with the signature of its plugin table
 * (siconos/kernel/PluginTypes.hpp, VectorFunctionOfTime). Built by siconos_peer.build_plugin:
 *     cc -O2 -shared -fPIC -o forcing_plugin.so forcing_plugin.c -lm
 */
#include <math.h>

void forcing(double time, unsigned int size, double* fext, unsigned int zsize, double* z) {
  (void)zsize;
  const double s = z[0] * sin(z[1] * time);
  for (unsigned int i = 0; i < size; ++i) fext[i] = z[2 + i] * s;
}
