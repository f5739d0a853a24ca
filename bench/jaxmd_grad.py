"""JAX-MD's grad-of-simulate on the systems of `lagra bench gradient`, for its ratio of
gradient time to forward time (CPU, float64, the second call of each, so JIT compilation is not
counted). Run: python bench/jaxmd_grad.py [--quick]   (needs PyPI jax-md; not run in CI)."""
import sys
import time

import jax
import jax.numpy as jnp
from jax import lax

jax.config.update("jax_enable_x64", True)
from jax_md import energy, partition, simulate, space  # noqa: E402


def fcc(cells, density):
    a = (4.0 / density) ** (1.0 / 3.0)
    basis = jnp.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    grid = jnp.stack(jnp.meshgrid(*[jnp.arange(cells)] * 3, indexing="ij"), -1).reshape(-1, 3)
    return ((grid[:, None, :] + basis[None]).reshape(-1, 3) * a), cells * a


def study(cells, steps, neighbour_list):
    x0, box = fcc(cells, 0.8442)
    n = x0.shape[0]
    v0 = jax.random.normal(jax.random.PRNGKey(0), (n, 3)) * jnp.sqrt(1.44)
    v0 = v0 - v0.mean(0)
    disp, shift = space.periodic(box)
    dt = 0.005

    if neighbour_list:
        neighbor_fn, energy_fn_of = energy.lennard_jones_neighbor_list, None
        nbrs_fn, e_fn = energy.lennard_jones_neighbor_list(disp, box, sigma=1.0, epsilon=1.0, r_onset=2.4, r_cutoff=2.5, dr_threshold=0.3)
        nbrs = nbrs_fn.allocate(x0)

        def final_energy(eps):
            efn = lambda x, neighbor: e_fn(x, neighbor=neighbor, epsilon=eps)
            init, apply = simulate.nve(efn, shift, dt)
            state = init(jax.random.PRNGKey(1), x0, kT=1.44, neighbor=nbrs)

            def body(i, carry):
                st, nb = carry
                st = apply(st, neighbor=nb)
                nb = nb.update(st.position)
                return st, nb

            st, nb = lax.fori_loop(0, steps, body, (state, nbrs))
            return efn(st.position, nb)
    else:
        def final_energy(eps):
            efn = energy.lennard_jones_pair(disp, sigma=1.0, epsilon=eps, r_onset=2.4, r_cutoff=2.5)
            init, apply = simulate.nve(efn, shift, dt)
            state = init(jax.random.PRNGKey(1), x0, kT=1.44)
            st = lax.fori_loop(0, steps, lambda i, s: apply(s), state)
            return efn(st.position)

    forward = jax.jit(final_energy)
    gradient = jax.jit(jax.grad(final_energy))
    forward(1.0).block_until_ready()
    gradient(1.0).block_until_ready()
    best_f = best_g = float("inf")
    for _ in range(3):
        t = time.perf_counter(); forward(1.0).block_until_ready(); best_f = min(best_f, time.perf_counter() - t)
        t = time.perf_counter(); gradient(1.0).block_until_ready(); best_g = min(best_g, time.perf_counter() - t)
    print(f"| jax-md {n} atoms | {steps} | {best_f:.3f} s | {best_g:.3f} s | {best_g / best_f:.2f} |")


print("| system | steps | forward | grad | ratio |\n|---|---|---|---|---|")
study(4, 1000, False)
if "--quick" not in sys.argv:
    study(20, 100, True)
