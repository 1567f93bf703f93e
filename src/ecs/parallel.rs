//! Where the parallel stages run: bevy's `ComputeTaskPool` or a pool owned by the plugin.
use bevy_ecs::prelude::*;
use bevy_tasks::{ComputeTaskPool, TaskPool, TaskPoolBuilder};

/// The threads the parallel stages use (see [`StochasticCollisionPlugin::threads`]).
///
/// [`StochasticCollisionPlugin::threads`]: super::StochasticCollisionPlugin::threads
#[derive(Resource)]
pub struct CollisionTaskPool {
    own: Option<TaskPool>,
    inline: bool,
}

impl CollisionTaskPool {
    /// `None`: bevy's `ComputeTaskPool`; `Some(1)` (or 0): inline; `Some(n)`: `n` own threads.
    pub fn new(threads: Option<usize>) -> Self {
        match threads {
            None => Self {
                own: None,
                inline: false,
            },
            Some(0 | 1) => Self {
                own: None,
                inline: true,
            },
            // The calling thread helps (it ticks the pool while it waits): n − 1 pool threads.
            Some(n) => Self {
                own: Some(
                    TaskPoolBuilder::new()
                        .num_threads(n - 1)
                        .thread_name("stochastic_collision".into())
                        .build(),
                ),
                inline: false,
            },
        }
    }

    /// Number of threads working on a parallel stage.
    pub fn threads(&self) -> usize {
        if self.inline {
            1
        } else if let Some(pool) = &self.own {
            pool.thread_num() + 1
        } else {
            compute_pool().thread_num().max(1)
        }
    }

    /// Maps `f` over `chunks` of `items` in parallel; the results come back in chunk order
    /// (deterministic whatever the thread count).
    pub(crate) fn map_chunks<T: Sync, R: Send + 'static>(
        &self,
        items: &[T],
        chunk: usize,
        f: impl Fn(&[T]) -> R + Sync,
    ) -> Vec<R> {
        let chunk = chunk.max(1);
        if self.inline || items.len() <= chunk {
            return items.chunks(chunk).map(&f).collect();
        }
        let f = &f;
        match &self.own {
            // The pool's threads and the calling thread: exactly `n` threads work.
            Some(pool) => pool.scope(|s| {
                for c in items.chunks(chunk) {
                    s.spawn(async move { f(c) });
                }
            }),
            // The calling system may itself run on the compute pool: it must help.
            None => compute_pool().scope(|s| {
                for c in items.chunks(chunk) {
                    s.spawn(async move { f(c) });
                }
            }),
        }
    }

    /// Like [`map_chunks`](Self::map_chunks), but each chunk's results go into one of `outs`
    /// (resized to the number of chunks, each cleared): buffers kept from run to run, so a
    /// stage that runs every frame does not allocate (and fault in) fresh memory each time.
    pub(crate) fn map_chunks_into<T: Sync, R: Send>(
        &self,
        items: &[T],
        chunk: usize,
        outs: &mut Vec<Vec<R>>,
        f: impl Fn(&[T], &mut Vec<R>) + Sync,
    ) {
        let chunk = chunk.max(1);
        outs.resize_with(items.len().div_ceil(chunk), Vec::new);
        let mut work: Vec<(&[T], &mut Vec<R>)> = items.chunks(chunk).zip(outs.iter_mut()).collect();
        self.for_each_mut(&mut work, 1, |(c, out)| {
            out.clear();
            f(c, out);
        });
    }

    /// Runs `f` on every item of `items` (mutably) in parallel chunks.
    pub(crate) fn for_each_mut<T: Send>(
        &self,
        items: &mut [T],
        chunk: usize,
        f: impl Fn(&mut T) + Sync,
    ) {
        self.for_each_chunk_mut(items, chunk, |c| c.iter_mut().for_each(&f));
    }

    /// Runs `f` on `chunk`-sized pieces of `items` (mutably) in parallel; pieces start in
    /// order, so the first items are taken up first.
    pub(crate) fn for_each_chunk_mut<T: Send>(
        &self,
        items: &mut [T],
        chunk: usize,
        f: impl Fn(&mut [T]) + Sync,
    ) {
        let chunk = chunk.max(1);
        if self.inline || items.len() <= chunk {
            items.chunks_mut(chunk).for_each(f);
            return;
        }
        let f = &f;
        match &self.own {
            Some(pool) => {
                pool.scope(|s| {
                    for c in items.chunks_mut(chunk) {
                        s.spawn(async move { f(c) });
                    }
                });
            }
            None => {
                compute_pool().scope(|s| {
                    for c in items.chunks_mut(chunk) {
                        s.spawn(async move { f(c) });
                    }
                });
            }
        }
    }

    /// A chunk size giving each thread a few chunks (load balance) of at least `min` items.
    pub(crate) fn chunk_size(&self, n: usize, min: usize) -> usize {
        n.div_ceil(self.threads() * 4).max(min)
    }
}

fn compute_pool() -> &'static ComputeTaskPool {
    ComputeTaskPool::get_or_init(|| {
        TaskPoolBuilder::new()
            .num_threads(bevy_tasks::available_parallelism())
            .build()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn threads_used(pool: &CollisionTaskPool) -> usize {
        let items: Vec<u32> = (0..16).collect();
        let ids = pool.map_chunks(&items, 2, |_| {
            std::thread::sleep(std::time::Duration::from_millis(5));
            std::thread::current().id()
        });
        let mut ids: Vec<String> = ids.iter().map(|id| format!("{id:?}")).collect();
        ids.sort();
        ids.dedup();
        ids.len()
    }

    #[test]
    fn own_pool_runs_chunks_on_that_many_threads() {
        assert_eq!(threads_used(&CollisionTaskPool::new(Some(1))), 1);
        assert_eq!(threads_used(&CollisionTaskPool::new(Some(2))), 2);
        assert_eq!(threads_used(&CollisionTaskPool::new(Some(3))), 3);
    }
}
