#!/usr/bin/env python3
"""What a GPU user would pick instead: The DCNet of scripts/torch_dcnet.py
(same layers, EM5 closed-loop loss, RMSProp) trained on a CUDA device, in the arrangements a
PyTorch user would try: eager at the paper's batch 256, the whole step captured in a CUDA graph,
larger batches, and many models at once (torch.func vmap over stacked parameters, as a sweep or
the 1134-combination grid would want). Prints one line per arrangement: samples/s summed over
models. Random windows [batch, 6, 10]; timings after warm-up, synchronised.
"""
import sys, time, torch, torch.nn as nn
from torch.func import functional_call, grad, stack_module_state, vmap

C, H = 16, 128
import os
dev = torch.device(os.environ.get('DEV', 'cuda'))
torch.backends.cudnn.benchmark = True


class Net(nn.Module):
    def __init__(s):
        super().__init__()
        c, h = C, H
        s.c1 = nn.Sequential(nn.Conv1d(3, c, 2), nn.LeakyReLU(0.05), nn.Conv1d(c, c, 2), nn.LeakyReLU(0.05))
        s.c2 = nn.Sequential(nn.Conv2d(1, c, 2, dilation=(3, 1)), nn.LeakyReLU(0.05), nn.Conv2d(c, c, 2),
                             nn.LeakyReLU(0.05), nn.Conv2d(c, c, 2), nn.LeakyReLU(0.05))
        s.fc = nn.Sequential(nn.Linear(c * 8 + c * 7, h), nn.Tanh(), nn.Dropout(0.3), nn.Linear(h, h // 2),
                             nn.Tanh(), nn.Dropout(0.3), nn.Linear(h // 2, h // 4), nn.Tanh(), nn.Dropout(0.3),
                             nn.Linear(h // 4, 6))

    def forward(s, x):
        a = s.c1(x[:, :3] - x[:, 3:]).flatten(1)
        b = s.c2(x.unsqueeze(1)).flatten(1)
        return s.fc(torch.cat([a, b], 1))


def loss_of(out, x, gt):
    k = out[:, :3, None]; b = out[:, 3:, None]
    cal = (x[:, :3] - b / 100) / (1 + k / 100)
    return ((cal - gt) ** 2).sum(1).mean()


def timed(step, n):
    for _ in range(20): step()
    torch.cuda.synchronize()
    t0 = time.perf_counter()
    for _ in range(n): step()
    torch.cuda.synchronize()
    return time.perf_counter() - t0


def single(batch, graph, n=600):
    torch.manual_seed(0)
    net = Net().to(dev)
    opt = torch.optim.RMSprop(net.parameters(), lr=5e-4, capturable=graph)
    x = torch.randn(batch, 6, 10, device=dev); gt = torch.randn(batch, 3, 10, device=dev)

    def step():
        opt.zero_grad(set_to_none=not graph)
        loss = loss_of(net(x), x, gt); loss.backward(); opt.step()
    if not graph:
        dt = timed(step, n)
    else:
        s = torch.cuda.Stream(); s.wait_stream(torch.cuda.current_stream())
        with torch.cuda.stream(s):
            for _ in range(5): step()
        torch.cuda.current_stream().wait_stream(s)
        g = torch.cuda.CUDAGraph()
        with torch.cuda.graph(g):
            step()
        dt = timed(g.replay, n)
    return n * batch / dt, dt / n


def stacked(models, batch, graph, n=300):
    torch.manual_seed(0)
    nets = [Net().to(dev) for _ in range(models)]
    params, bufs = stack_module_state(nets)
    base = Net().to('meta')
    sq = {k: torch.zeros_like(v) for k, v in params.items()}
    x = torch.randn(models, batch, 6, 10, device=dev); gt = torch.randn(models, batch, 3, 10, device=dev)

    def one(p, b, xx, gg):
        return loss_of(functional_call(base, (p, b), (xx,)), xx, gg)
    g_all = vmap(grad(one), in_dims=(0, 0, 0, 0), randomness='different')

    def step():
        gr = g_all(params, bufs, x, gt)
        with torch.no_grad():
            for k, p in params.items():
                gk = gr[k]
                sq[k].mul_(0.99).addcmul_(gk, gk, value=0.01)
                p.addcdiv_(gk, sq[k].sqrt().add_(1e-8), value=-5e-4)
    if not graph:
        dt = timed(step, n)
    else:
        s = torch.cuda.Stream(); s.wait_stream(torch.cuda.current_stream())
        with torch.cuda.stream(s):
            for _ in range(5): step()
        torch.cuda.current_stream().wait_stream(s)
        gph = torch.cuda.CUDAGraph()
        with torch.cuda.graph(gph):
            step()
        dt = timed(gph.replay, n)
    return n * batch * models / dt, dt / n


def main():
    print(f'device: {torch.cuda.get_device_name(0)}, torch {torch.__version__}', flush=True)
    rows = []
    def run(name, f, *a):
        try:
            r, st = f(*a)
            line = f'{name}: {r:,.0f} samples/s ({st * 1e3:.3f} ms/step)'
        except Exception as e:  # report and go on: one arrangement failing says something too
            line = f'{name}: failed: {type(e).__name__}: {str(e)[:200]}'
        print(line, flush=True); rows.append(line)
    run('eager, 1 model, batch 256', single, 256, False)
    run('CUDA graph, 1 model, batch 256', single, 256, True)
    run('eager, 1 model, batch 4096', single, 4096, False, 300)
    run('CUDA graph, 1 model, batch 4096', single, 4096, True, 300)
    run('eager, 1 model, batch 65536', single, 65536, False, 100)
    for m in (16, 128, 1024):
        run(f'vmap eager, {m} models, batch 256 each', stacked, m, 256, False, 100)
        run(f'vmap CUDA graph, {m} models, batch 256 each', stacked, m, 256, True, 100)
    print('SUMMARY'); print('\n'.join(rows))


if __name__ == '__main__':
    main()
